//! NIfTI files as nibabel (PyPI) writes them, made at test time: oblique
//! and axis-aligned, sform and qform, NIfTI-1 and NIfTI-2, one file, a
//! gzipped file and a .hdr/.img pair, big-endian, scaled; each marker
//! voxel lands where nibabel's affine puts it, the values are nibabel's,
//! and bad files are refused by the field at fault.

use anari_library_caveray::data::{load_nifti, DataError};
use anari_library_caveray::scene::{StructuredVolume, VolumeError, Voxels};
use glam::Vec3;

use crate::fixtures;

/// Writes the fixtures into `dir` with nibabel and returns what nibabel
/// says of each: its affine, its marker's index and world position, and
/// the marker's value.
const WRITE: &str = r#"
import json, sys
import numpy as np, nibabel as nib
out = {}
def marked(dtype, shape=(20, 16, 12), marker=(5, 7, 3), value=1000):
    d = np.zeros(shape, dtype=dtype)
    d[2:-2, 2:-2, 2:-2] = 100
    d[marker] = value
    return d
th = np.radians(30)
oblique = np.eye(4)
oblique[:3, :3] = np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]]) @ np.diag([0.8, 1.2, 2.5])
oblique[:3, 3] = [-10, 20, 35]
tilted = np.eye(4)
c, s = np.cos(np.radians(20)), np.sin(np.radians(20))
tilted[:3, :3] = np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) @ np.diag([-0.9, 0.9, 1.5])
tilted[:3, 3] = [40, -30, 5]
def save(name, img, marker=(5, 7, 3)):
    nib.save(img, name)
    back = nib.load(name)
    a = back.affine
    out[name] = {"affine": a.tolist(), "marker": list(marker),
                 "world": (a @ [*marker, 1])[:3].tolist(),
                 "value": float(back.get_fdata()[marker])}
img = nib.Nifti1Image(marked(np.int16), oblique); img.header.set_xyzt_units("mm")
save("oblique_sform.nii.gz", img)
img = nib.Nifti1Image(marked(np.uint8, value=250), tilted)
img.set_qform(tilted, code=1); img.set_sform(None, code=0)
save("tilted_qform.nii", img)
img = nib.Nifti2Image(marked(np.float32), oblique)
save("oblique.nii2.nii", img)
img = nib.Nifti1Pair(marked(np.uint16, value=60000), tilted)
save("pair.hdr", img)
be = nib.Nifti1Image(marked(np.dtype(">i2")), oblique)
save("big_endian.nii", be)
scaled = nib.Nifti1Image(marked(np.int16, value=300), oblique)
scaled.header.set_slope_inter(0.5, -20.0)
save("scaled.nii", scaled)
nib.save(nib.Nifti1Image(np.zeros((4, 4, 4, 3), np.float32), np.eye(4)), "series.nii")
json.dump(out, sys.stdout)
"#;

#[test]
fn nibabel_files_load_with_their_markers_where_their_headers_put_them() {
    let Some((dir, said)) = fixtures::written_by("nibabel", WRITE, "nifti") else {
        return;
    };
    let fixtures = said.as_object().unwrap();
    assert_eq!(fixtures.len(), 6);
    for (name, truth) in fixtures {
        let nifti = load_nifti(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        // The affine, to nibabel's own (single precision in NIfTI-1).
        let affine = nifti.header.affine;
        for r in 0..3 {
            for c in 0..4 {
                let want = truth["affine"][r][c].as_f64().unwrap();
                let got = affine.row(r)[c];
                assert!(
                    (got - want).abs() < 1e-5 * (1.0 + want.abs()),
                    "{name}: affine[{r}][{c}] {got} vs {want}"
                );
            }
        }
        // The brightest voxel is the marker, with nibabel's value, and
        // lands where nibabel puts it, within half a voxel.
        let half = 0.5 * nifti.header.spacing.abs().min_element();
        fixtures::marker_lands(name, &nifti.volume, nifti.transform(), truth, half);
        fixtures::kept_in_its_type(name, &nifti.volume, nifti.header.dtype);
        // Uncompressed voxels are the file's own bytes, mapped (nibabel
        // writes every file little-endian, this machine's order); gzipped
        // ones are read.
        let mapped = !name.ends_with(".gz");
        assert_eq!(nifti.volume.voxels().is_mapped(), mapped, "{name}");
    }
    // A series of volumes is refused by the dimension at fault.
    let e = load_nifti(&dir.join("series.nii")).err().unwrap();
    assert!(
        matches!(&e, DataError::Header { field, .. } if field == "dim[4]"),
        "{e}"
    );
    assert!(e.to_string().contains("one 3D volume"), "{e}");
}

#[test]
fn broken_nifti_files_are_refused_by_the_field_at_fault() {
    let dir = fixtures::scratch("nifti_broken");
    // A NIfTI-1 header by hand: 4 x 4 x 4 uint8, the voxels at 352.
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (i, d) in [3i16, 4, 4, 4, 1, 1, 1, 1].iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&2i16.to_le_bytes());
    h[72..74].copy_from_slice(&8i16.to_le_bytes());
    for i in 0..4 {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&1f32.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[344..348].copy_from_slice(b"n+1\0");
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    };
    let mut whole = h.clone();
    whole.extend((0..64u8).collect::<Vec<_>>());
    let good = load_nifti(&write("good.nii", &whole)).unwrap();
    assert_eq!(good.volume.value(63), 63.0);
    let field_of = |bytes: Vec<u8>, name: &str| match load_nifti(&write(name, &bytes)) {
        Err(DataError::Header { field, why, .. }) => format!("{field}: {why}"),
        other => panic!("{name}: {:?}", other.map(|n| n.header)),
    };
    // Truncated voxels, a bad magic, an unknown type, a zero dimension, an
    // offset inside the header, a size that is neither version's.
    let short = field_of(whole[..352 + 40].to_vec(), "short.nii");
    assert!(
        short.starts_with("voxels: 4x4x4 uint8 needs 64 bytes"),
        "{short}"
    );
    let mut bad = whole.clone();
    bad[344..348].copy_from_slice(b"abc\0");
    assert!(field_of(bad, "magic.nii").starts_with("magic:"));
    let mut bad = whole.clone();
    bad[70..72].copy_from_slice(&32i16.to_le_bytes());
    assert!(field_of(bad, "complex.nii").starts_with("datatype: 32 is not a scalar type"));
    let mut bad = whole.clone();
    bad[44..46].copy_from_slice(&0i16.to_le_bytes());
    assert!(field_of(bad, "zero.nii").starts_with("dim[2]: 0 voxels"));
    let mut bad = whole.clone();
    bad[108..112].copy_from_slice(&100f32.to_le_bytes());
    assert!(field_of(bad, "offset.nii").starts_with("vox_offset: 100 lies inside"));
    let mut bad = whole.clone();
    bad[0..4].copy_from_slice(&350i32.to_le_bytes());
    assert!(field_of(bad, "size.nii").starts_with("sizeof_hdr: 350"));
    let e = field_of(whole[..100].to_vec(), "cut.nii");
    assert!(e.starts_with("header: 100 bytes"), "{e}");
    // A voxel count past what caveray takes is refused before reading.
    let mut huge = whole.clone();
    for i in 1..4 {
        huge[40 + 2 * i..42 + 2 * i].copy_from_slice(&32000i16.to_le_bytes());
    }
    let e = load_nifti(&write("huge.nii", &huge)).err().unwrap();
    assert!(matches!(e, DataError::TooManyVoxels { .. }), "{e}");
    // So is one whose voxel count overflows 64 bits (NIfTI-2 dims reach
    // 2^32 - 1 each), here and in the volume itself.
    let e = StructuredVolume::new(
        glam::UVec3::splat(u32::MAX),
        Voxels::U8(Vec::new().into()),
        Vec3::ZERO,
        Vec3::ONE,
    )
    .err()
    .unwrap();
    assert!(matches!(e, VolumeError::TooManyVoxels { .. }), "{e}");
}
