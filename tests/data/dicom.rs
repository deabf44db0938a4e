//! DICOM series as pydicom (PyPI) writes them, made at test time, as
//! Debian's dcmtk converts them (RLE, JPEG lossless, JPEG baseline;
//! implicit VR, big-endian, deflated) and as pydicom compresses them
//! (JPEG 2000 lossless and lossy, JPEG-LS): an oblique CT of 12 stored
//! bits with a rescale, its files named and numbered out of order, and the
//! same volume as one enhanced CT file; an axial 8-bit series beside a
//! one-slice scout of another series. Each marker voxel lands where the
//! headers put it (in RAS+), the largest series of a folder is the one
//! read, a slice's file stands for its series, and broken series are
//! refused by the field at fault.

use std::path::Path;
use std::process::Command;

use crate::{common, fixtures};
use anari_library_caveray::data::{load_volume_file, DataError};
use serde_json::Value;

/// Writes the series with pydicom; prints each folder's marker index,
/// its world position in RAS+, its value and the value range.
const WRITE: &str = r#"
import json, os, sys
import numpy as np
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.uid import ExplicitVRLittleEndian, generate_uid, CTImageStorage, MRImageStorage

study = generate_uid()
def rot(axis, deg):
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    if axis == "x":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])

def ds_text(v):
    return [float(f"{x:.8g}") for x in v]

def series(folder, shape, dtype, bits_stored, turn, spacing, origin, slope, intercept,
           marker, marker_stored, modality="CT", order=None, edit=None, prefix="IM"):
    """Writes a series of shape (columns, rows, slices); returns its truth."""
    os.makedirs(folder, exist_ok=True)
    nx, ny, nz = shape
    uid = generate_uid()
    row, col, normal = turn[:, 0], turn[:, 1], turn[:, 2]
    low = -5 if np.issubdtype(dtype, np.signedinteger) else 0
    order = order or list(range(nz))
    for n, k in enumerate(order):
        px = np.zeros((ny, nx), dtype=dtype)
        px[2:-2, 2:-2] = 100
        if k == 0:
            px[0, 0] = low
        if k == marker[2]:
            px[marker[1], marker[0]] = marker_stored
        ipp = np.array(origin, float) + k * spacing[2] * normal
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = CTImageStorage if modality == "CT" else MRImageStorage
        meta.MediaStorageSOPInstanceUID = generate_uid()
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        ds = Dataset()
        ds.file_meta = meta
        ds.SOPClassUID = meta.MediaStorageSOPClassUID
        ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
        ds.Modality = modality
        ds.StudyInstanceUID = study
        ds.SeriesInstanceUID = uid
        # Numbered and named against the slices' order along the normal.
        ds.InstanceNumber = n + 1
        ds.ImagePositionPatient = ds_text(ipp)
        ds.ImageOrientationPatient = ds_text(list(row) + list(col))
        ds.PixelSpacing = ds_text([spacing[1], spacing[0]])
        ds.SliceThickness = spacing[2]
        ds.Rows, ds.Columns = ny, nx
        ds.SamplesPerPixel = 1
        ds.PhotometricInterpretation = "MONOCHROME2"
        ds.BitsAllocated = px.itemsize * 8
        ds.BitsStored = bits_stored
        ds.HighBit = bits_stored - 1
        ds.PixelRepresentation = 1 if np.issubdtype(dtype, np.signedinteger) else 0
        ds.RescaleSlope = slope
        ds.RescaleIntercept = intercept
        ds.PixelData = px.tobytes()
        # A sequence before the pixels, as scanners write several.
        ref = Dataset()
        ref.ReferencedSOPClassUID = CTImageStorage
        ref.ReferencedSOPInstanceUID = generate_uid()
        ref.Rows = 999
        ds.ReferencedImageSequence = [ref]
        if edit:
            edit(ds, k)
        ds.save_as(os.path.join(folder, f"{prefix}{n:04d}"), enforce_file_format=True)
    ipp0 = np.array(ds_text(origin))
    world = ipp0 + marker[0] * spacing[0] * row + marker[1] * spacing[1] * col + marker[2] * spacing[2] * normal
    lo = min(low, 0) * slope + intercept
    hi = max(100, marker_stored) * slope + intercept
    return {"marker": list(marker), "world": (np.array([-1, -1, 1]) * world).tolist(),
            "value": marker_stored * slope + intercept, "range": [lo, hi]}

out = {}
oblique = rot("z", 25) @ rot("x", 15)
out["oblique"] = series("oblique", (36, 32, 12), np.int16, 12, oblique, (0.7, 0.8, 2.5),
                        (-40.0, 25.5, 110.0), 1.0, -1024.0, (5, 7, 3), 2000,
                        order=[7, 2, 11, 0, 5, 9, 1, 4, 10, 3, 8, 6])
out["axial"] = series("axial", (40, 34, 9), np.uint8, 8, np.eye(3), (1.2, 1.2, 3.0),
                      (10.0, -20.0, -30.0), 2.0, 0.0, (11, 4, 6), 250, modality="MR")
# A scout of another series in the same folder: fewer slices, not read.
series("axial", (40, 34, 1), np.uint8, 8, rot("x", 90), (1.0, 1.0, 1.0), (0, 0, 0), 1.0, 0.0,
       (0, 0, 0), 7, modality="MR", prefix="SCOUT")
with open(os.path.join("axial", "README.txt"), "w") as f:
    f.write("not a slice\n")
# Broken series.
series("gap", (8, 8, 6), np.uint8, 8, np.eye(3), (1, 1, 2), (0, 0, 0), 1, 0, (1, 1, 1), 9,
       order=[0, 1, 2, 4, 5])
def twin(ds, k):
    if k == 3:
        ds.ImagePositionPatient = ds_text([0, 0, 2 * 2])
series("twin", (8, 8, 6), np.uint8, 8, np.eye(3), (1, 1, 2), (0, 0, 0), 1, 0, (1, 1, 1), 9, edit=twin)
def unspaced(ds, k):
    del ds.PixelSpacing
series("unspaced", (8, 8, 2), np.uint8, 8, np.eye(3), (1, 1, 2), (0, 0, 0), 1, 0, (1, 1, 1), 9, edit=unspaced)
def tilted(ds, k):
    if k == 1:
        ds.ImageOrientationPatient = ds_text([1, 0, 0, 0, 0.8, 0.6])
series("tilted", (8, 8, 3), np.uint8, 8, np.eye(3), (1, 1, 2), (0, 0, 0), 1, 0, (1, 1, 1), 9, edit=tilted)
json.dump(out, sys.stdout)
"#;

/// Writes, beside WRITE's series, their copies compressed by pydicom
/// (JPEG 2000 through pylibjpeg-openjpeg, JPEG-LS through pyjpegls), the
/// lossy one also as pydicom decodes it, and an enhanced CT: one file of
/// frames stored out of order, placed by its per-frame functional groups
/// and sharing their orientation, spacing and rescale. Prints nothing.
const COMPRESS: &str = r#"
from pydicom import dcmread
from pydicom.uid import JPEG2000Lossless, JPEG2000, JPEGLSLossless, EnhancedCTImageStorage

def copies(source, target, uid, **kw):
    os.makedirs(target, exist_ok=True)
    for f in sorted(os.listdir(source)):
        if not f.endswith(".txt"):
            ds = dcmread(os.path.join(source, f))
            ds.compress(uid, **kw)
            ds.save_as(os.path.join(target, f), enforce_file_format=True)

copies("oblique", "oblique_j2k", JPEG2000Lossless)
copies("oblique", "oblique_jls", JPEGLSLossless)
copies("axial", "axial_j2k_lossy", JPEG2000, j2k_cr=[4])
os.makedirs("axial_j2k_decoded")
for f in sorted(os.listdir("axial_j2k_lossy")):
    ds = dcmread(os.path.join("axial_j2k_lossy", f))
    ds.decompress()
    ds.save_as(os.path.join("axial_j2k_decoded", f), enforce_file_format=True)

def enhanced(folder, shape, turn, spacing, origin, slope, intercept, marker, stored, order):
    nx, ny, nz = shape
    row, col, normal = turn[:, 0], turn[:, 1], turn[:, 2]
    frames, per_frame = [], []
    for k in order:
        px = np.zeros((ny, nx), np.int16)
        px[2:-2, 2:-2] = 100
        px[0, 0] = -5 if k == 0 else 0
        if k == marker[2]:
            px[marker[1], marker[0]] = stored
        frames.append(px)
        position = Dataset()
        position.ImagePositionPatient = ds_text(np.array(origin, float) + k * spacing[2] * normal)
        content = Dataset()
        content.InStackPositionNumber = k + 1
        item = Dataset()
        item.PlanePositionSequence = [position]
        item.FrameContentSequence = [content]
        per_frame.append(item)
    measures, plane, values = Dataset(), Dataset(), Dataset()
    measures.PixelSpacing = ds_text([spacing[1], spacing[0]])
    measures.SliceThickness = spacing[2]
    plane.ImageOrientationPatient = ds_text(list(row) + list(col))
    values.RescaleSlope, values.RescaleIntercept, values.RescaleType = slope, intercept, "HU"
    shared = Dataset()
    shared.PixelMeasuresSequence = [measures]
    shared.PlaneOrientationSequence = [plane]
    shared.PixelValueTransformationSequence = [values]
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = EnhancedCTImageStorage
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = Dataset()
    ds.file_meta = meta
    ds.SOPClassUID, ds.SOPInstanceUID = EnhancedCTImageStorage, meta.MediaStorageSOPInstanceUID
    ds.Modality, ds.StudyInstanceUID, ds.SeriesInstanceUID = "CT", study, generate_uid()
    ds.NumberOfFrames, ds.Rows, ds.Columns = nz, ny, nx
    ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 12, 11, 1
    ds.SharedFunctionalGroupsSequence = [shared]
    ds.PerFrameFunctionalGroupsSequence = per_frame
    ds.PixelData = np.stack(frames).tobytes()
    os.makedirs(folder)
    ds.save_as(os.path.join(folder, "enhanced.dcm"), enforce_file_format=True)
    ds.compress(JPEG2000Lossless)
    os.makedirs(folder + "_j2k")
    ds.save_as(os.path.join(folder + "_j2k", "enhanced.dcm"), enforce_file_format=True)

enhanced("enhanced", (36, 32, 12), oblique, (0.7, 0.8, 2.5), (-40.0, 25.5, 110.0), 1.0, -1024.0,
         (5, 7, 3), 2000, [7, 2, 11, 0, 5, 9, 1, 4, 10, 3, 8, 6])
"#;

#[test]
fn pydicom_series_load_with_their_markers_where_their_headers_put_them() {
    let Some((dir, said)) = fixtures::written_by("pydicom", WRITE, "dicom") else {
        return;
    };
    for name in ["oblique", "axial"] {
        let truth = &said[name];
        let file = load_volume_file(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(file.anatomical && file.units == "mm", "{name}");
        fixtures::kept_in_its_type(name, &file.volume, file.dtype);
        fixtures::marker_lands(name, &file.volume, file.transform(), truth, 1e-3);
        let (lo, hi) = file.volume.value_range();
        assert_eq!(
            [f64::from(lo), f64::from(hi)],
            [number(&truth["range"][0]), number(&truth["range"][1])],
            "{name}: values as stored bits, sign and rescale give them"
        );
    }
    let axial = load_volume_file(&dir.join("axial")).unwrap();
    let detail = |key: &str| {
        axial
            .details
            .iter()
            .find(|(k, _)| *k == key)
            .unwrap()
            .1
            .clone()
    };
    assert_eq!(detail("slices"), 9, "the largest series of the folder");
    assert_eq!(detail("series_in_folder"), 2);
    assert_eq!(detail("files_skipped"), 1, "README.txt");
    // One slice's file stands for its series: the scout's is a series of one.
    let scout = std::fs::read_dir(dir.join("axial"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| load_volume_file(p).is_ok_and(|f| f.volume.dims().z == 1));
    assert!(scout.is_some(), "the scout is read as a series of its own");
    let slice = dir.join("axial").join("IM0003");
    let whole = load_volume_file(&slice).unwrap();
    assert_eq!(whole.volume.dims().z, 9, "{}: its series", slice.display());
    // The tool takes the folder with no other flag.
    let folder = dir.join("oblique");
    let caveray = |args: &[&str]| {
        let run = Command::new(env!("CARGO_BIN_EXE_caveray"))
            .args(args)
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        run.stdout
    };
    let doc: Value = serde_json::from_slice(&caveray(&[
        "inspect",
        "--volume",
        folder.to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    assert_eq!(doc["format"], "DICOM");
    assert_eq!(doc["dims"], serde_json::json!([36, 32, 12]));
    assert_eq!(doc["modality"], "CT");
    assert_eq!(doc["slices"], 12);
    let rig = Path::new(env!("CARGO_MANIFEST_DIR")).join("cave_configs/cologne_5wall.toml");
    caveray(&[
        "render",
        "--config",
        rig.to_str().unwrap(),
        "--volume",
        folder.to_str().unwrap(),
        "--scale",
        "0.02",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(dir.join("out/timings.json").is_file());
}

#[test]
fn series_in_every_transfer_syntax_read_as_dcmtk_wrote_them() {
    let Some((dir, said)) = fixtures::written_by("pydicom", WRITE, "dicom_compressed") else {
        return;
    };
    if dcmtk_copies(&dir).is_none() {
        return;
    }
    let reference = |name: &str| load_volume_file(&dir.join(name)).unwrap();
    for (name, source, syntax) in [
        ("oblique_rle", "oblique", "1.2.840.10008.1.2.5"),
        ("oblique_lossless", "oblique", "1.2.840.10008.1.2.4.70"),
        ("oblique_implicit", "oblique", "1.2.840.10008.1.2"),
        ("oblique_big", "oblique", "1.2.840.10008.1.2.2"),
        ("oblique_deflated", "oblique", "1.2.840.10008.1.2.1.99"),
    ] {
        let file = load_volume_file(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let shown = file
            .details
            .iter()
            .find(|(k, _)| *k == "transfer_syntax")
            .unwrap()
            .1
            .clone();
        assert_eq!(shown, syntax, "{name}");
        fixtures::marker_lands(name, &file.volume, file.transform(), &said[source], 1e-3);
        assert_eq!(
            values(&file),
            values(&reference(source)),
            "{name}: lossless"
        );
    }
    // Baseline JPEG is lossy (and dcmtk folds the rescale into its 8
    // bits): decoded as dcmtk's own decoder decodes it, to within the
    // rounding of an inverse DCT.
    let lossy = load_volume_file(&dir.join("axial_baseline")).unwrap();
    let theirs = load_volume_file(&dir.join("axial_decoded")).unwrap();
    assert_eq!(lossy.transform(), reference("axial").transform());
    let worst = values(&lossy)
        .iter()
        .zip(values(&theirs))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(
        worst <= 2.0,
        "baseline JPEG: {worst} from dcmdjpeg's values"
    );
}

#[test]
fn pydicom_compressed_series_and_an_enhanced_multiframe_file_load() {
    let script = format!("{WRITE}{COMPRESS}");
    let Some((dir, said)) = fixtures::written_by("pydicom", &script, "dicom_pydicom") else {
        return;
    };
    let load =
        |name: &str| load_volume_file(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    let reference = load("oblique");
    let half_voxel = 0.5 * 0.7;
    for (name, syntax) in [
        ("oblique_j2k", "1.2.840.10008.1.2.4.90"),
        ("enhanced", "1.2.840.10008.1.2.1"),
        ("enhanced_j2k", "1.2.840.10008.1.2.4.90"),
    ] {
        let file = load(name);
        assert_eq!(detail(&file, "transfer_syntax"), syntax, "{name}");
        fixtures::marker_lands(
            name,
            &file.volume,
            file.transform(),
            &said["oblique"],
            half_voxel,
        );
        assert!(values(&file) == values(&reference), "{name}: lossless");
        assert_eq!(file.transform(), reference.transform(), "{name}");
    }
    let one = load("enhanced/enhanced.dcm");
    assert_eq!(detail(&one, "slices"), 12, "the frames of one file");
    // Lossy JPEG 2000: as pydicom's decoder (OpenJPEG) decodes it.
    let lossy = load("axial_j2k_lossy");
    assert_eq!(lossy.transform(), load("axial").transform());
    let theirs = values(&load("axial_j2k_decoded"));
    let worst = values(&lossy)
        .iter()
        .zip(&theirs)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(worst <= 2.0, "JPEG 2000: {worst} from OpenJPEG's values");
    assert!(values(&lossy) != values(&load("axial")), "lossy");
    // JPEG-LS has no decoder in pure Rust: refused by name, with a way out.
    match load_volume_file(&dir.join("oblique_jls")) {
        Err(DataError::Header { field, why, .. }) => {
            assert_eq!(field, "TransferSyntaxUID");
            assert!(why.contains("JPEG-LS") && why.contains("dcmdjpls"), "{why}");
        }
        other => panic!("JPEG-LS: {:?}", other.map(|f| f.dtype)),
    }
}

fn detail(file: &anari_library_caveray::data::VolumeFile, key: &str) -> Value {
    let found = file.details.iter().find(|(k, _)| *k == key);
    found.unwrap_or_else(|| panic!("no {key}")).1.clone()
}

/// The voxels of `file` in order.
fn values(file: &anari_library_caveray::data::VolumeFile) -> Vec<f32> {
    (0..file.volume.voxels().len())
        .map(|i| file.volume.value(i))
        .collect()
}

/// Copies of the written series by dcmtk: compressed by dcmcrle and
/// dcmcjpeg, in the other uncompressed syntaxes by dcmconv (implicit VR,
/// big-endian, deflated), and dcmdjpeg's decoding of the lossy one (scripts/deps
/// installs dcmtk); None where it is missing.
fn dcmtk_copies(dir: &Path) -> Option<()> {
    if Command::new("dcmcjpeg").arg("--version").output().is_err() {
        common::missing("dcmtk (dcmcjpeg, dcmcrle; scripts/deps installs it)");
        return None;
    }
    let copy = |tool: &str, flags: &[&str], from: &str, to: &str| {
        std::fs::create_dir_all(dir.join(to)).unwrap();
        for entry in std::fs::read_dir(dir.join(from)).unwrap().flatten() {
            let name = entry.file_name();
            if name.to_string_lossy().ends_with(".txt") {
                continue;
            }
            let run = Command::new(tool)
                .args(flags)
                .arg(entry.path())
                .arg(dir.join(to).join(&name))
                .output()
                .unwrap();
            assert!(
                run.status.success(),
                "{tool}: {}",
                String::from_utf8_lossy(&run.stderr)
            );
        }
    };
    copy("dcmcrle", &[], "oblique", "oblique_rle");
    copy("dcmconv", &["+ti"], "oblique", "oblique_implicit");
    copy("dcmconv", &["+tb"], "oblique", "oblique_big");
    copy("dcmconv", &["+td"], "oblique", "oblique_deflated");
    copy("dcmcjpeg", &["+e1"], "oblique", "oblique_lossless");
    copy("dcmcjpeg", &["+eb", "+q", "90"], "axial", "axial_baseline");
    copy("dcmdjpeg", &[], "axial_baseline", "axial_decoded");
    Some(())
}

#[test]
fn broken_series_are_refused_by_the_field_at_fault() {
    let Some((dir, _)) = fixtures::written_by("pydicom", WRITE, "dicom_broken") else {
        return;
    };
    let refused = |name: &str| -> String {
        match load_volume_file(&dir.join(name)) {
            Err(DataError::Header { field, why, .. }) => format!("{field}: {why}"),
            Err(other) => panic!("{name}: {other}"),
            Ok(_) => panic!("{name}: read"),
        }
    };
    for (name, says) in [
        (
            "gap",
            "ImagePositionPatient: the slices are not evenly spaced: 4.000 mm",
        ),
        ("twin", "ImagePositionPatient"),
        ("unspaced", "PixelSpacing: missing"),
        (
            "tilted",
            "ImageOrientationPatient: the slices of the series are not parallel",
        ),
    ] {
        let why = refused(name);
        assert!(why.starts_with(says), "{name}: {why}");
    }
    assert!(refused("twin").contains("lie at the same position"));
    // A length past the end of the file is refused by its element before
    // anything is reserved for it.
    let mut bytes = std::fs::read(dir.join("gap/IM0000")).unwrap();
    let header = [0xE0, 0x7F, 0x10, 0x00, b'O', b'B', 0, 0];
    let at = bytes
        .windows(8)
        .rposition(|w| w == header)
        .expect("PixelData as OB");
    bytes[at + 8..at + 12].copy_from_slice(&0xFFFF_FFF0u32.to_le_bytes());
    let huge = fixtures::scratch("dicom_huge_length");
    std::fs::write(huge.join("IM0000"), &bytes).unwrap();
    match load_volume_file(&huge.join("IM0000")) {
        Err(DataError::Header { field, why, .. }) => {
            assert_eq!(field, "PixelData");
            assert!(
                why.starts_with("4294967280 bytes declared where 64 are left"),
                "{why}"
            );
        }
        other => panic!("a length past the end: {:?}", other.map(|f| f.dtype)),
    }
    // A folder without slices says why its first file is not one.
    let empty = fixtures::scratch("dicom_not_slices");
    std::fs::write(empty.join("notes.dcm"), b"not DICOM at all").unwrap();
    let why = match load_volume_file(&empty) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("read"),
    };
    assert!(
        why.contains("no DICOM image slices") && why.contains("notes.dcm"),
        "{why}"
    );
}

fn number(v: &Value) -> f64 {
    v.as_f64().unwrap()
}
