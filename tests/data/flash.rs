//! FLASH's AMR files as h5py writes them in FLASH's layout, made at test
//! time: a root block and two of its eight children (the parent kept, as
//! FLASH keeps it), a linear density and a second variable. The field is
//! the linear function wherever a level has a whole stencil, across the
//! level boundary too; `--array` picks a variable and names the others
//! when it is not one; `caveray inspect` prints the levels and `render`
//! draws every wall. Without the `hdf5` feature the tool refuses such a
//! file by name.

use std::process::Command;

use crate::fixtures;

/// Refine levels 1 (the root over [0, 1]^3) and 2 (its octants at x = 0
/// and x = 1/2, y and z below 1/2), blocks of 8^3 cells; dens = 1 + x + 2y
/// + 3z at the cell centres, temp = 300 - x.
const WRITE: &str = r#"
import json
import numpy as np, h5py
n = 8
los = [(0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.5, 0.0, 0.0)]
sizes = [1.0, 0.5, 0.5]
levels = np.array([1, 2, 2], dtype=np.int32)
types = np.array([2, 1, 1], dtype=np.int32)
boxes = np.zeros((3, 3, 2))
dens = np.zeros((3, n, n, n))
temp = np.zeros((3, n, n, n), dtype=np.float32)
for b, (lo, s) in enumerate(zip(los, sizes)):
    for a in range(3):
        boxes[b, a] = [lo[a], lo[a] + s]
    c = (np.arange(n) + 0.5) * s / n
    z, y, x = np.meshgrid(lo[2] + c, lo[1] + c, lo[0] + c, indexing="ij")
    dens[b] = 1 + x + 2 * y + 3 * z
    temp[b] = 300 - x
with h5py.File("sedov_hdf5_chk_0001", "w") as f:
    f["refine level"] = levels
    f["node type"] = types
    f["bounding box"] = boxes
    f["block size"] = boxes[:, :, 1] - boxes[:, :, 0]
    f["coordinates"] = boxes.mean(axis=2)
    f["dens"] = dens
    f["temp"] = temp
    f["unknown names"] = np.array([[b"dens"], [b"temp"]], dtype="S4")
    scalars = np.array([(b"nxb", n), (b"nyb", n), (b"nzb", n)], dtype=[("name", "S80"), ("value", "<i4")])
    f["integer scalars"] = scalars
print(json.dumps({"sedov_hdf5_chk_0001": "flash"}))
"#;

fn caveray(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_caveray"))
        .args(args)
        .env("CAVERAY_BACKEND", "cpu")
        .output()
        .unwrap()
}

#[cfg(feature = "hdf5")]
#[test]
fn a_flash_file_holds_its_levels_and_a_linear_field_across_them() {
    use anari_library_caveray::data::load_flash;
    use glam::Vec3;
    let Some((dir, _)) = fixtures::written_by("h5py", WRITE, "flash") else {
        return;
    };
    let path = dir.join("sedov_hdf5_chk_0001");
    let file = load_flash(&path, None).unwrap();
    assert_eq!(file.variable, "dens");
    assert_eq!(file.variables, ["dens", "temp"]);
    assert_eq!(file.block_cells, [8, 8, 8]);
    assert_eq!(file.leaves, Some(2));
    let amr = &file.amr;
    assert_eq!(amr.block_count(), 3);
    let levels = amr.levels();
    assert_eq!((levels[0].width, levels[0].cells), (1.0, 1024));
    assert_eq!((levels[1].width, levels[1].cells), (2.0, 512));
    let (lo, hi) = amr.bounds();
    assert!(lo.abs_diff_eq(Vec3::ZERO, 1e-6) && hi.abs_diff_eq(Vec3::ONE, 1e-6));
    // Within the coarse cells' centres (1/16 to 15/16), the fine blocks'
    // edges at y = z = 1/2 included.
    let dens = |p: Vec3| 1.0 + p.x + 2.0 * p.y + 3.0 * p.z;
    let mut worst: f32 = 0.0;
    for i in 0..500 {
        let t = i as f32 / 499.0;
        let p = Vec3::new(
            0.07 + 0.86 * t,
            0.3 + 0.4 * (t * 7.0).fract(),
            0.45 + 0.1 * t,
        );
        worst = worst.max((amr.sample_world(p) - dens(p)).abs());
    }
    assert!(worst < 1e-4, "off by {worst}");
    let temp = load_flash(&path, Some("temp")).unwrap();
    let p = Vec3::new(0.3, 0.2, 0.2);
    assert!((temp.amr.sample_world(p) - (300.0 - p.x)).abs() < 1e-3);
    let Err(e) = load_flash(&path, Some("pres")) else {
        panic!("pres is not in the file");
    };
    assert!(
        e.to_string()
            .contains("pres: no such variable; the file has dens, temp"),
        "{e}"
    );

    let inspect = caveray(&["inspect", "--volume", path.to_str().unwrap()]);
    let said = String::from_utf8_lossy(&inspect.stdout);
    assert!(inspect.status.success(), "{said}");
    assert!(
        said.contains("FLASH (HDF5)") && said.contains("3 of 8x8x8 cells, 2 of them leaves"),
        "{said}"
    );
    assert!(said.contains("cells 2 wide: 512 cells"), "{said}");

    let out = dir.join("out");
    let render = caveray(&[
        "render",
        "--config",
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/cave_configs/cologne_5wall.toml"
        ),
        "--volume",
        path.to_str().unwrap(),
        "--array",
        "temp",
        "--scale",
        "0.05",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        render.status.success(),
        "{}",
        String::from_utf8_lossy(&render.stderr)
    );
    let pngs = std::fs::read_dir(&out)
        .unwrap()
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "png"))
        .count();
    assert!(pngs >= 10, "{pngs} images");
}

#[cfg(not(feature = "hdf5"))]
#[test]
fn without_hdf5_a_flash_file_is_refused_by_name() {
    let Some((dir, _)) = fixtures::written_by("h5py", WRITE, "flash") else {
        return;
    };
    let path = dir.join("sedov_hdf5_chk_0001");
    let rig = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cave_configs/cologne_5wall.toml"
    );
    let out = dir.join("out");
    let render = caveray(&[
        "render",
        "--config",
        rig,
        "--volume",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let said = String::from_utf8_lossy(&render.stderr);
    assert!(!render.status.success());
    assert!(said.contains("built without HDF5"), "{said}");
}
