//! VTK image data as SimpleITK (legacy `.vtk`, binary) and pyevtk (`.vti`,
//! raw appended data) write it, made at test time, and `.vti` files
//! written here in the ways VTK's own writer has (text, base64 inline as
//! one run or two, zlib-compressed blocks with 64-bit headers, base64
//! appended data, an oblique direction and an extent that does not start
//! at 0): each lands where its origin, spacing and direction put it, with
//! its values, and bad files are refused by the field at fault.

use base64::engine::general_purpose::STANDARD;
use base64::Engine;
use glam::{DMat3, DVec3};

use crate::fixtures;
use anari_library_caveray::data::{load_vtk, DataError, VolumeFile, VolumeFormat};

/// Writes the fixtures; prints each one's marker index, its world
/// position as the writer's own reader (SimpleITK) or VTK's convention
/// (origin + spacing * index, for pyevtk) places it, and its value.
const WRITE: &str = r#"
import json, sys
import numpy as np, SimpleITK as sitk
from pyevtk.hl import imageToVTK
out = {}
def marked(dtype, value, size=(20, 16, 12), marker=(5, 7, 3)):
    a = np.zeros(size, dtype=dtype)
    a[2:-2, 2:-2, 2:-2] = 100
    a[marker] = value
    return a
def itk(name, dtype, value, spacing, origin, marker=(5, 7, 3)):
    img = sitk.GetImageFromArray(marked(dtype, value).transpose(2, 1, 0).copy())
    img.SetSpacing(spacing)
    img.SetOrigin(origin)
    sitk.WriteImage(img, name)
    back = sitk.ReadImage(name)
    out[name] = {"marker": list(marker), "world": list(back.TransformIndexToPhysicalPoint(marker)),
                 "value": float(back[marker]), "dtype": str(sitk.GetArrayViewFromImage(back).dtype)}
def evtk(name, dtype, value, spacing, origin, marker=(5, 7, 3)):
    a = marked(dtype, value)
    imageToVTK("./" + name, origin=origin, spacing=spacing, pointData={"density": np.asfortranarray(a)})
    world = np.array(origin) + np.array(spacing) * np.array(marker)
    out[name + ".vti"] = {"marker": list(marker), "world": world.tolist(), "value": float(a[marker]),
                          "dtype": str(a.dtype)}
itk("short.vtk", np.int16, 1000, (0.7, 1.1, 2.0), (12.0, -7.5, 30.0))
itk("float.vtk", np.float32, 1000.25, (1.2, 1.2, 3.0), (-5.0, 4.0, 2.0))
itk("bytes.vtk", np.uint8, 250, (2.0, 1.0, 0.5), (0.0, 0.0, 0.0))
evtk("evtk_float", np.float32, 1000.25, (0.5, 0.25, 2.0), (1.0, 2.0, 3.0))
evtk("evtk_int", np.int32, 100000, (1.5, 1.5, 1.5), (-3.0, 0.0, 9.0))
json.dump(out, sys.stdout)
"#;

#[test]
fn simpleitk_and_pyevtk_files_load_with_their_markers_where_they_put_them() {
    let Some((dir, said)) = fixtures::written_by("SimpleITK and pyevtk", WRITE, "vtk") else {
        return;
    };
    let fixtures = said.as_object().unwrap();
    assert_eq!(fixtures.len(), 5);
    for (name, truth) in fixtures {
        let image = load_vtk(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let legacy = name.ends_with(".vtk");
        let format = if legacy {
            VolumeFormat::VtkLegacy
        } else {
            VolumeFormat::VtkXml
        };
        assert_eq!(image.format, format, "{name}");
        assert!(!image.anatomical, "{name}");
        assert_eq!(image.units, "unknown", "{name}");
        assert_eq!(image.dtype, truth["dtype"].as_str().unwrap(), "{name}");
        let encoding = if legacy { "binary" } else { "raw" };
        assert_eq!(detail(&image, "encoding"), encoding, "{name}");
        fixtures::marker_lands(name, &image.volume, image.transform(), truth, 1e-3);
        fixtures::kept_in_its_type(name, &image.volume, image.dtype);
    }
}

fn detail(image: &VolumeFile, key: &str) -> serde_json::Value {
    image
        .details
        .iter()
        .find(|(k, _)| *k == key)
        .map(|(_, v)| v.clone())
        .unwrap_or_default()
}

/// The grid of the hand-written files: 5 x 4 x 3 points, each its own
/// value.
const DIMS: [usize; 3] = [5, 4, 3];
const EXTENT: &str = "0 4 0 3 0 2";

fn value(n: usize) -> f32 {
    let (i, j, k) = (n % 5, n / 5 % 4, n / 20);
    (i + 10 * j + 100 * k) as f32 - 50.5
}

fn values() -> Vec<f32> {
    (0..DIMS.iter().product()).map(value).collect()
}

fn data() -> Vec<u8> {
    values().iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn text() -> String {
    values()
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

/// A `.vti` file: the root's attributes besides its type and byte order,
/// the image's besides its whole extent, its pieces, and what follows the
/// image (appended data).
fn vti(root: &str, image: &str, pieces: &str, appended: &[u8]) -> Vec<u8> {
    let mut file = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" {root}>\n\
         <ImageData WholeExtent=\"{EXTENT}\" {image}>\n{pieces}</ImageData>\n"
    )
    .into_bytes();
    file.extend(appended);
    file.extend(b"</VTKFile>\n");
    file
}

/// One piece of the whole extent, whose point data holds `arrays`.
fn piece(arrays: &str) -> String {
    format!(
        "<Piece Extent=\"{EXTENT}\">\n<PointData Scalars=\"v\">\n{arrays}\n</PointData>\n<CellData>\n</CellData>\n</Piece>\n"
    )
}

fn array(attributes: &str, content: &str) -> String {
    format!("<DataArray type=\"Float32\" Name=\"v\" NumberOfComponents=\"1\" {attributes}>\n{content}\n</DataArray>")
}

/// zlib-compressed blocks of at most 64 bytes of `data`, as VTK's
/// compressor writes them: the header (blocks, block size, the last's
/// size, each one's compressed size; 64-bit words) and the blocks.
fn zlib_blocks(data: &[u8]) -> (Vec<u8>, Vec<u8>) {
    use std::io::Write;
    let chunks: Vec<&[u8]> = data.chunks(64).collect();
    let mut blocks = Vec::new();
    let mut header: Vec<u64> = vec![chunks.len() as u64, 64, (data.len() % 64) as u64];
    for chunk in &chunks {
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(chunk).unwrap();
        let block = z.finish().unwrap();
        header.push(block.len() as u64);
        blocks.extend(block);
    }
    (
        header.iter().flat_map(|w| w.to_le_bytes()).collect(),
        blocks,
    )
}

fn with_header(data: &[u8]) -> Vec<u8> {
    let mut run = (data.len() as u32).to_le_bytes().to_vec();
    run.extend(data);
    run
}

#[test]
fn vti_files_in_each_of_vtks_encodings_load_their_values_where_they_say() {
    let dir = fixtures::scratch("vti_written");
    let plain = "Origin=\"1 -2 3.5\" Spacing=\"0.5 0.25 2\"";
    let decoy = "<DataArray type=\"Float64\" Name=\"decoy\" format=\"ascii\">9</DataArray>\n";
    let separate = STANDARD.encode((data().len() as u32).to_le_bytes()) + &STANDARD.encode(data());
    let (zheader, zblocks) = zlib_blocks(&data());
    let zlib = STANDARD.encode(&zheader) + &STANDARD.encode(&zblocks);
    // A decoy array first in the appended data, the grid's after it.
    let decoy_run = STANDARD.encode(8u32.to_le_bytes()) + &STANDARD.encode([0u8; 8]);
    let appended =
        format!("<AppendedData encoding=\"base64\">\n  _{decoy_run}{separate}\n</AppendedData>\n");
    let appended_arrays = format!(
        "<DataArray type=\"Float64\" Name=\"decoy\" format=\"appended\" offset=\"0\"/>\n{}",
        array(
            &format!("format=\"appended\" offset=\"{}\"", decoy_run.len()),
            ""
        )
    );
    let th = 25f64.to_radians();
    let (c, s) = (th.cos(), th.sin());
    let oblique = format!(
        "Origin=\"12 -7.5 30\" Spacing=\"0.7 1.1 2\" Direction=\"{c} {} 0 {s} {c} 0 0 0 1\"",
        -s
    );
    let cases: Vec<(&str, Vec<u8>, &str, &str)> = vec![
        (
            "ascii.vti",
            vti(
                "",
                plain,
                &piece(&format!("{decoy}{}", array("format=\"ascii\"", &text()))),
                b"",
            ),
            "ascii",
            plain,
        ),
        (
            "separate.vti",
            vti(
                "header_type=\"UInt32\"",
                plain,
                &piece(&array("format=\"binary\"", &separate)),
                b"",
            ),
            "binary",
            plain,
        ),
        (
            "one_run.vti",
            vti(
                "",
                plain,
                &piece(&array(
                    "format=\"binary\"",
                    &STANDARD.encode(with_header(&data())),
                )),
                b"",
            ),
            "binary",
            plain,
        ),
        (
            "zlib.vti",
            vti(
                "header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\"",
                plain,
                &piece(&array("format=\"binary\"", &zlib)),
                b"",
            ),
            "binary",
            plain,
        ),
        (
            "appended.vti",
            vti("", plain, &piece(&appended_arrays), appended.as_bytes()),
            "appended",
            plain,
        ),
        (
            "oblique.vti",
            vti(
                "",
                &oblique,
                &piece(&array("format=\"ascii\"", &text())),
                b"",
            ),
            "ascii",
            &oblique,
        ),
    ];
    for (name, bytes, encoding, _) in &cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let image = load_vtk(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(image.format, VolumeFormat::VtkXml, "{name}");
        assert_eq!(detail(&image, "encoding"), *encoding, "{name}");
        assert_eq!(detail(&image, "array"), "v", "{name}");
        assert_eq!(image.dtype, "float32", "{name}");
        assert_eq!(image.volume.dims().to_array(), [5, 4, 3], "{name}");
        let got: Vec<f32> = (0..image.volume.voxels().len())
            .map(|i| image.volume.value(i))
            .collect();
        assert_eq!(got, values(), "{name}");
        let (origin, m) = if name.starts_with("oblique") {
            let turn = DMat3::from_cols(DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0), DVec3::Z);
            (
                DVec3::new(12.0, -7.5, 30.0),
                turn * DMat3::from_diagonal(DVec3::new(0.7, 1.1, 2.0)),
            )
        } else {
            (
                DVec3::new(1.0, -2.0, 3.5),
                DMat3::from_diagonal(DVec3::new(0.5, 0.25, 2.0)),
            )
        };
        for index in [
            DVec3::ZERO,
            DVec3::new(4.0, 3.0, 2.0),
            DVec3::new(1.0, 2.0, 1.0),
        ] {
            let want = origin + m * index;
            let got = image.affine.transform_point3(index);
            assert!(
                got.distance(want) < 1e-9,
                "{name}: {index} lands at {got}, not {want}"
            );
        }
    }
    // Raw appended float32 in this machine's byte order, aligned: mapped
    // from the file, not copied; one byte off its alignment: read.
    for pad in [0, 1] {
        let run = with_header(&data());
        let pieces = piece(&array("format=\"appended\" offset=\"0\"", ""));
        let start = vti("", plain, &pieces, b"").len() - b"</VTKFile>\n".len();
        let tag = b"<AppendedData encoding=\"raw\">\n_";
        // The numbers begin after the tag and the run's 4-byte size.
        let mut spaces = (4 - (start + tag.len() + 4) % 4) % 4 + pad;
        let mut appended = Vec::new();
        while spaces > 0 {
            appended.push(b' ');
            spaces -= 1;
        }
        appended.extend(tag);
        appended.extend(&run);
        appended.extend(b"\n</AppendedData>\n");
        let path = dir.join(format!("raw{pad}.vti"));
        std::fs::write(&path, vti("", plain, &pieces, &appended)).unwrap();
        let image = load_vtk(&path).unwrap_or_else(|e| panic!("raw{pad}.vti: {e}"));
        assert_eq!(detail(&image, "encoding"), "raw");
        let got: Vec<f32> = (0..image.volume.voxels().len())
            .map(|i| image.volume.value(i))
            .collect();
        assert_eq!(got, values(), "raw{pad}.vti");
        let aligned = cfg!(target_endian = "little") && pad == 0;
        assert_eq!(image.volume.voxels().is_mapped(), aligned, "raw{pad}.vti");
    }
    // An extent from (2, 0, 1): its first point is 2 and 1 steps along.
    let moved = String::from_utf8(cases[5].1.clone())
        .unwrap()
        .replace(EXTENT, "2 6 0 3 1 3");
    let path = dir.join("moved.vti");
    std::fs::write(&path, moved).unwrap();
    let image = load_vtk(&path).unwrap();
    let first = image.affine.transform_point3(DVec3::ZERO);
    let turn = DMat3::from_cols(DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0), DVec3::Z);
    let want = DVec3::new(12.0, -7.5, 30.0) + turn * DVec3::new(2.0 * 0.7, 0.0, 2.0);
    assert!(first.distance(want) < 1e-9, "{first} is not {want}");
}

#[test]
fn legacy_ascii_files_pass_over_cell_data_and_field_data() {
    let dir = fixtures::scratch("vtk_ascii");
    let file = format!(
        "# vtk DataFile Version 3.0\nwritten by hand\nASCII\nDATASET STRUCTURED_POINTS\n\
         DIMENSIONS 5 4 3\nASPECT_RATIO 0.5 0.25 2\nORIGIN 1 -2 3.5\n\
         FIELD FieldData 1\nTIME 1 1 double\n2.5\n\
         CELL_DATA 24\nSCALARS cells int 1\nLOOKUP_TABLE default\n{}\n\
         POINT_DATA 60\nVECTORS arrows float\n{}\nSCALARS v float\nLOOKUP_TABLE default\n{}\n",
        vec!["7"; 24].join(" "),
        vec!["0.5"; 180].join(" "),
        text()
    );
    let path = dir.join("ascii.vtk");
    std::fs::write(&path, file).unwrap();
    let image = load_vtk(&path).unwrap();
    let got: Vec<f32> = (0..image.volume.voxels().len())
        .map(|i| image.volume.value(i))
        .collect();
    assert_eq!(got, values());
    assert_eq!(detail(&image, "encoding"), "ascii");
    assert_eq!(detail(&image, "array"), "v");
    let far = image.affine.transform_point3(DVec3::new(4.0, 3.0, 2.0));
    assert_eq!(far, DVec3::new(3.0, -1.25, 7.5));
}

#[test]
fn broken_vtk_files_are_refused_by_the_field_at_fault() {
    let dir = fixtures::scratch("vtk_broken");
    let refused = |name: &str, bytes: &[u8]| -> String {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        match load_vtk(&path) {
            Err(DataError::Header { field, why, .. }) => format!("{field}: {why}"),
            Err(other) => panic!("{name}: {other}"),
            Ok(_) => panic!("{name}: read"),
        }
    };
    let legacy = |encoding: &str, rest: &str| {
        format!("# vtk DataFile Version 3.0\ntitle\n{encoding}\n{rest}").into_bytes()
    };
    let points = "DATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n";
    let mut short_binary = legacy(
        "BINARY",
        &format!("{points}POINT_DATA 8\nSCALARS v float\nLOOKUP_TABLE default\n"),
    );
    short_binary.extend([0u8; 31]);
    let plain = "Spacing=\"1 1 1\"";
    let ascii = piece(&array("format=\"ascii\"", &text()));
    let xml_cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "int64.vti",
            vti("", plain, &ascii.replace("Float32", "Int64"), b""),
            "type: 'Int64'",
        ),
        (
            "few.vti",
            vti(
                "",
                plain,
                &piece(&array(
                    "format=\"ascii\"",
                    &text()[..text().rfind(' ').unwrap()],
                )),
                b"",
            ),
            "DataArray: 'v': 59 values; 60 are needed",
        ),
        (
            "many.vti",
            vti(
                "",
                plain,
                &piece(&array("format=\"ascii\"", &(text() + " 1"))),
                b"",
            ),
            "DataArray: 'v': more than the 60 values",
        ),
        (
            "size.vti",
            vti(
                "",
                plain,
                &piece(&array(
                    "format=\"binary\"",
                    &STANDARD.encode(with_header(&data()[4..])),
                )),
                b"",
            ),
            "DataArray: 'v': 236 bytes; the grid needs 240",
        ),
        (
            "pieces.vti",
            vti("", plain, &(ascii.clone() + &ascii), b""),
            "Piece: 2 pieces",
        ),
        (
            "base64.vti",
            vti(
                "",
                plain,
                &piece(&array("format=\"binary\"", "AAAA!!!!AAAA")),
                b"",
            ),
            "DataArray: 'v': not base64",
        ),
        (
            "cells.vti",
            vti(
                "",
                plain,
                &ascii
                    .replace("PointData", "CellData")
                    .replace("<CellData>\n</CellData>", ""),
                b"",
            ),
            "CellData: the file has cell data only",
        ),
        (
            "lz4.vti",
            vti("compressor=\"vtkLZ4DataCompressor\"", plain, &ascii, b""),
            "compressor: 'vtkLZ4DataCompressor'",
        ),
        (
            "poly.vti",
            String::from_utf8(vti("", plain, &ascii, b""))
                .unwrap()
                .replace("type=\"ImageData\"", "type=\"PolyData\"")
                .into_bytes(),
            "type: 'PolyData'",
        ),
        (
            "flat.vti",
            vti("", "Direction=\"1 0 0 1 0 0 0 0 1\"", &ascii, b""),
            "Direction: the spacing and direction span no volume",
        ),
        (
            "marker.vti",
            vti(
                "",
                plain,
                &piece(&array("format=\"appended\" offset=\"0\"", "")),
                b"<AppendedData encoding=\"raw\">\n</AppendedData>\n",
            ),
            "AppendedData: no '_' marks where its data begins",
        ),
    ];
    let legacy_cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "poly.vtk",
            legacy("ASCII", "DATASET POLYDATA\nPOINTS 1 float\n0 0 0\n"),
            "DATASET: 'POLYDATA'",
        ),
        (
            "cells.vtk",
            legacy("ASCII", &format!("{points}CELL_DATA 1\nSCALARS c float\nLOOKUP_TABLE default\n1.5\n")),
            "CELL_DATA: the file has cell data only",
        ),
        (
            "few.vtk",
            legacy("ASCII", &format!("{points}POINT_DATA 8\nSCALARS v float 1\nLOOKUP_TABLE default\n1 2 3 4 5 6 7\n")),
            "SCALARS: 7 values; 8 are needed",
        ),
        ("short.vtk", short_binary, "SCALARS: 8 float32 values need 32 bytes; the file holds 31"),
        (
            "rgb.vtk",
            legacy("ASCII", &format!("{points}POINT_DATA 8\nSCALARS v float 3\n")),
            "SCALARS: 3 components",
        ),
        (
            "count.vtk",
            legacy("ASCII", &format!("{points}POINT_DATA 9\nSCALARS v float\n")),
            "POINT_DATA: 9 points; DIMENSIONS 2 2 2 make 8",
        ),
        (
            "long.vtk",
            legacy("ASCII", &format!("{points}POINT_DATA 8\nSCALARS v vtkIdType\n")),
            "SCALARS: 'vtkIdType'",
        ),
        ("encoding.vtk", legacy("UTF-8", points), "format: 'UTF-8' is neither ASCII nor BINARY"),
        ("text.vtk", b"a text file\n".to_vec(), "format: neither legacy VTK"),
    ];
    for (name, bytes, start) in xml_cases.iter().chain(&legacy_cases) {
        let got = refused(name, bytes);
        assert!(got.starts_with(start), "{name}: {got}");
    }
}
