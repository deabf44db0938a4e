//! MetaImage files as SimpleITK (PyPI) writes them, made at test time: an
//! oblique int16 `.mha`, a compressed one, a `.mhd` with its float32 data
//! file, a uint8 one turned about and a 2D one; each marker voxel lands
//! where ITK's own index-to-physical map puts it (turned from LPS into
//! RAS+), and bad headers are refused by the field at fault.

use crate::fixtures;
use anari_library_caveray::data::{load_metaimage, DataError, VolumeFormat};

/// Writes the fixtures with SimpleITK; prints each one's marker index,
/// its world position (ITK's, LPS, turned into RAS+) and its value. The
/// oblique direction is not symmetric, so that reading ITK's direction
/// matrix transposed puts the marker elsewhere.
const WRITE: &str = r#"
import json, sys
import numpy as np, SimpleITK as sitk
out = {}
th = np.radians(25)
turn = [np.cos(th), -np.sin(th), 0, np.sin(th), np.cos(th), 0, 0, 0, 1]
def marked(dtype, size=(20, 16, 12), marker=(5, 7, 3), value=1000):
    a = np.zeros(size[::-1], dtype=dtype)
    if len(size) == 3:
        a[2:-2, 2:-2, 2:-2] = 100
    img = sitk.GetImageFromArray(a)
    img[marker] = value
    return img
def save(name, img, direction, spacing, origin, marker=(5, 7, 3), **kw):
    img.SetDirection(direction)
    img.SetSpacing(spacing)
    img.SetOrigin(origin)
    sitk.WriteImage(img, name, **kw)
    back = sitk.ReadImage(name)
    world = list(back.TransformIndexToPhysicalPoint(marker)) + [0.0] * (3 - len(marker))
    index = list(marker) + [0] * (3 - len(marker))
    out[name] = {"marker": index, "world": (np.array([-1, -1, 1]) * world).tolist(),
                 "value": float(back[marker]), "dtype": str(sitk.GetArrayViewFromImage(back).dtype)}
save("oblique.mha", marked(np.int16), turn, (0.7, 1.1, 2.0), (12.0, -7.5, 30.0))
save("compressed.mha", marked(np.uint16, value=60000), turn, (0.9, 0.9, 1.5), (-5.0, 4.0, 2.0), useCompression=True)
save("float.mhd", marked(np.float32, value=1000.25), [1, 0, 0, 0, 1, 0, 0, 0, 1], (1.2, 1.2, 3.0), (0.0, 0.0, 0.0))
save("turned.mha", marked(np.uint8, value=250), [1, 0, 0, 0, -1, 0, 0, 0, -1], (2.0, 1.0, 0.5), (3.0, 4.0, 5.0))
save("flat.mha", marked(np.uint8, size=(20, 16), marker=(5, 7), value=200), [0, 1, 1, 0], (0.5, 0.25), (1.0, 2.0), marker=(5, 7))
json.dump(out, sys.stdout)
"#;

#[test]
fn simpleitk_files_load_with_their_markers_where_itk_puts_them() {
    let Some((dir, said)) = fixtures::written_by("SimpleITK", WRITE, "metaimage") else {
        return;
    };
    let fixtures = said.as_object().unwrap();
    assert_eq!(fixtures.len(), 5);
    for (name, truth) in fixtures {
        let image = load_metaimage(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(image.format, VolumeFormat::MetaImage);
        assert!(image.anatomical, "{name}");
        assert_eq!(image.units, "mm", "{name}");
        assert_eq!(image.dtype, truth["dtype"].as_str().unwrap(), "{name}");
        let compressed = image
            .details
            .iter()
            .find(|(k, _)| *k == "compressed")
            .map(|(_, v)| v.as_bool().unwrap());
        assert_eq!(compressed, Some(name == "compressed.mha"), "{name}");
        // Uncompressed voxels are mapped where they are aligned for their
        // type (always for bytes, and in a data file of their own).
        let mapped = image.volume.voxels().is_mapped();
        match name.as_str() {
            "compressed.mha" => assert!(!mapped, "{name}"),
            "float.mhd" | "turned.mha" | "flat.mha" => assert!(mapped, "{name}"),
            _ => {}
        }
        fixtures::marker_lands(name, &image.volume, image.transform(), truth, 1e-3);
        fixtures::kept_in_its_type(name, &image.volume, image.dtype);
    }
    assert!(
        dir.join("float.raw").exists(),
        "SimpleITK wrote no data file"
    );
}

/// A `.mhd` whose voxels sit at the end of a data file after bytes of
/// its own (`HeaderSize = -1`), big-endian.
#[test]
fn a_detached_big_endian_file_read_from_its_end() {
    let dir = fixtures::scratch("metaimage_end");
    std::fs::write(
        dir.join("end.mhd"),
        "ObjectType = Image\nNDims = 3\nDimSize = 2 2 1\nElementType = MET_SHORT\n\
         ElementByteOrderMSB = True\nHeaderSize = -1\nElementDataFile = end.dat\n",
    )
    .unwrap();
    let mut data = b"a preamble of any length".to_vec();
    for v in [-2i16, 300, 7, -32768] {
        data.extend(v.to_be_bytes());
    }
    std::fs::write(dir.join("end.dat"), data).unwrap();
    let image = load_metaimage(&dir.join("end.mhd")).unwrap();
    let values: Vec<f32> = (0..4).map(|i| image.volume.value(i)).collect();
    assert_eq!(values, [-2.0, 300.0, 7.0, -32768.0]);
    // Big-endian numbers are read (and swapped), not mapped.
    assert!(!image.volume.voxels().is_mapped());
    // Little-endian ones after an even skip are mapped from the data file.
    std::fs::write(
        dir.join("skip.mhd"),
        "ObjectType = Image\nNDims = 3\nDimSize = 2 2 1\nElementType = MET_USHORT\n\
         HeaderSize = 4\nElementDataFile = skip.dat\n",
    )
    .unwrap();
    let mut data = b"skip".to_vec();
    for v in [2u16, 300, 7, 65535] {
        data.extend(v.to_le_bytes());
    }
    std::fs::write(dir.join("skip.dat"), data).unwrap();
    let image = load_metaimage(&dir.join("skip.mhd")).unwrap();
    assert!(image.volume.voxels().is_mapped());
    let values: Vec<f32> = (0..4).map(|i| image.volume.value(i)).collect();
    assert_eq!(values, [2.0, 300.0, 7.0, 65535.0]);
}

#[test]
fn broken_metaimage_headers_are_refused_by_the_field_at_fault() {
    let dir = fixtures::scratch("metaimage_broken");
    let header = |fields: &str| {
        let mut b = format!("ObjectType = Image\n{fields}").into_bytes();
        b.extend(0..64u8);
        b
    };
    let good = "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
    let path = dir.join("good.mha");
    std::fs::write(&path, header(good)).unwrap();
    assert_eq!(load_metaimage(&path).unwrap().volume.value(63), 63.0);
    std::fs::write(dir.join("short.raw"), [0u8; 10]).unwrap();
    let refused = |name: &str, fields: &str| -> String {
        let path = dir.join(name);
        std::fs::write(&path, header(fields)).unwrap();
        match load_metaimage(&path) {
            Err(DataError::Header { field, why, .. }) => format!("{field}: {why}"),
            Err(other) => panic!("{name}: {other}"),
            Ok(_) => panic!("{name}: read"),
        }
    };
    let cases = [
        ("nodims.mha", "NDims = 3\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n", "DimSize: missing"),
        ("type.mha", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_LONG_LONG\nElementDataFile = LOCAL\n", "ElementType: 'MET_LONG_LONG'"),
        ("rgb.mha", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementNumberOfChannels = 2\nElementDataFile = LOCAL\n", "ElementNumberOfChannels: 2"),
        ("short.mhd", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = short.raw\n", "voxels: 4x4x4 uint8 needs 64 bytes"),
        ("list.mhd", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = LIST\n", "ElementDataFile: 'LIST'"),
        ("pattern.mhd", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = slice%03d.raw 1 4 1\n", "ElementDataFile: 'slice%03d.raw 1 4 1'"),
        ("four.mha", "NDims = 4\nDimSize = 4 4 2 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n", "NDims: 4"),
        ("sizes.mha", "NDims = 3\nDimSize = 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n", "DimSize: 2 sizes for NDims 3"),
        ("zero.mha", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementSpacing = 1 0 1\nElementDataFile = LOCAL\n", "ElementSpacing: 0 along axis 1"),
        ("flat.mha", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nTransformMatrix = 1 0 0 1 0 0 0 0 1\nElementDataFile = LOCAL\n", "TransformMatrix: the spacing and directions span no volume"),
        ("nan.mha", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nOffset = 0 nan 0\nElementDataFile = LOCAL\n", "Offset: '0 nan 0' is not finite numbers"),
        ("zlib.mha", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nCompressedData = True\nElementDataFile = LOCAL\n", "CompressedData: the zlib stream"),
        ("text.mha", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nBinaryData = False\nElementDataFile = LOCAL\n", "BinaryData: False"),
        ("line.mha", "NDims = 3\nDimSize: 4 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n", "header: 'DimSize: 4 4 4' is not a 'Key = Value' line"),
    ];
    for (name, fields, start) in cases {
        let got = refused(name, fields);
        assert!(got.starts_with(start), "{name}: {got}");
    }
    let path = dir.join("end.mhd");
    std::fs::write(
        &path,
        "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\n",
    )
    .unwrap();
    let e = load_metaimage(&path).err().unwrap().to_string();
    assert!(e.contains("ElementDataFile: missing"), "{e}");
}
