//! NRRD files as pynrrd (PyPI) writes them, made at test time: an oblique
//! LPS scan gzipped, a RAS one raw and big-endian, a detached header with
//! its data file, and one with spacings only; each marker voxel lands
//! where the header's space directions and origin put it (turned into
//! RAS+), and bad headers are refused by the field at fault.

use crate::fixtures;
use anari_library_caveray::data::{load_nrrd, DataError};

/// Writes the fixtures with pynrrd; prints each one's marker index, its
/// world position in RAS+ and its value, and whether the file is in an
/// anatomical space.
const WRITE: &str = r#"
import json, sys
import numpy as np, nrrd
out = {}
def marked(dtype, shape=(20, 16, 12), marker=(5, 7, 3), value=1000):
    d = np.zeros(shape, dtype=dtype)
    d[2:-2, 2:-2, 2:-2] = 100
    d[marker] = value
    return d
th = np.radians(25)
oblique = (np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]]) @ np.diag([0.7, 1.1, 2.0])).T
def save(name, data, header, to_ras, marker=(5, 7, 3), **kw):
    nrrd.write(name, data, header, index_order="F", **kw)
    back, h = nrrd.read(name, index_order="F")
    dirs = h.get("space directions")
    origin = h.get("space origin", np.zeros(3))
    world = (np.asarray(origin, float) + np.asarray(dirs, float).T @ np.array(marker, float)) if dirs is not None else np.array(marker, float) * np.asarray(h.get("spacings", [1, 1, 1]), float)
    out[name] = {"marker": list(marker), "world": (np.array(to_ras) * world).tolist(),
                 "value": float(back[marker]), "ras": dirs is not None}
save("oblique_lps.nrrd", marked(np.int16),
     {"space": "left-posterior-superior", "space directions": oblique, "space origin": [12.0, -7.5, 30.0], "encoding": "gzip"},
     [-1, -1, 1])
save("ras_big.nrrd", marked(np.float32),
     {"space": "right-anterior-superior", "space directions": np.diag([0.9, 0.9, 1.5]), "space origin": [-5.0, 4.0, 2.0], "encoding": "raw", "endian": "big"},
     [1, 1, 1])
save("detached.nhdr", marked(np.uint16, value=60000),
     {"space": "left-posterior-superior", "space directions": np.diag([1.2, 1.2, 3.0]), "space origin": [0.0, 0.0, 0.0], "encoding": "raw"},
     [-1, -1, 1], detached_header=True)
save("spacings.nrrd", marked(np.uint8, value=250), {"spacings": [2.0, 1.0, 0.5], "encoding": "raw"}, [1, 1, 1])
json.dump(out, sys.stdout)
"#;

#[test]
fn pynrrd_files_load_with_their_markers_where_their_headers_put_them() {
    let Some((dir, said)) = fixtures::written_by("pynrrd", WRITE, "nrrd") else {
        return;
    };
    let fixtures = said.as_object().unwrap();
    assert_eq!(fixtures.len(), 4);
    for (name, truth) in fixtures {
        let nrrd = load_nrrd(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            nrrd.header.anatomical,
            truth["ras"].as_bool().unwrap(),
            "{name}"
        );
        fixtures::marker_lands(name, &nrrd.volume, nrrd.transform(), truth, 1e-3);
        fixtures::kept_in_its_type(name, &nrrd.volume, nrrd.header.dtype);
        // Raw voxels in this machine's byte order, inline or detached, are
        // the file's own bytes, mapped; gzipped or big-endian ones are read.
        let mapped = matches!(name.as_str(), "detached.nhdr" | "spacings.nrrd");
        assert_eq!(nrrd.volume.voxels().is_mapped(), mapped, "{name}");
    }
}

#[test]
fn broken_nrrd_headers_are_refused_by_the_field_at_fault() {
    let dir = fixtures::scratch("nrrd_broken");
    let header = |fields: &str| {
        let mut b = format!("NRRD0004\n{fields}\n").into_bytes();
        b.extend((0..64u8).collect::<Vec<_>>());
        b
    };
    let good = "type: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n";
    let path = dir.join("good.nrrd");
    std::fs::write(&path, header(good)).unwrap();
    assert_eq!(load_nrrd(&path).unwrap().volume.value(63), 63.0);
    let refused = |name: &str, fields: &str| -> String {
        let path = dir.join(name);
        std::fs::write(&path, header(fields)).unwrap();
        match load_nrrd(&path) {
            Err(DataError::Header { field, why, .. }) => format!("{field}: {why}"),
            other => panic!("{name}: {:?}", other.map(|n| n.header)),
        }
    };
    let cases = [
        ("type.nrrd", "type: block\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n", "type: 'block'"),
        ("dims.nrrd", "type: uint8\ndimension: 3\nsizes: 4 4\nencoding: raw\n", "sizes: 2 sizes for dimension 3"),
        ("four.nrrd", "type: uint8\ndimension: 4\nsizes: 3 4 4 4\nencoding: raw\n", "dimension: 4"),
        ("enc.nrrd", "type: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: bzip2\n", "encoding: 'bzip2'"),
        ("endian.nrrd", "type: short\ndimension: 3\nsizes: 4 4 2\nencoding: raw\n", "endian: missing"),
        ("short.nrrd", "type: uint8\ndimension: 3\nsizes: 4 4 8\nencoding: raw\n", "voxels: 4x4x8 uint8 needs 128 bytes"),
        ("dirs.nrrd", "type: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\nspace: RAS\nspace directions: (1,0,0) (0,1,0) (2,0,0)\n", "space directions: they are not finite or span no volume"),
        ("nospace.nrrd", "dimension: 3\nsizes: 4 4 4\nencoding: raw\n", "type: missing"),
    ];
    for (name, fields, start) in cases {
        let got = refused(name, fields);
        assert!(got.starts_with(start), "{name}: {got}");
    }
    let path = dir.join("magic.nrrd");
    std::fs::write(&path, b"NRRD0009\n").unwrap();
    assert!(load_nrrd(&path)
        .err()
        .unwrap()
        .to_string()
        .contains("magic"));
}
