//! Volume files written at test time by Python's own readers and writers
//! (nibabel, pynrrd, from target/pynari), and what a marker voxel in each
//! must come out as.

use std::path::{Path, PathBuf};
use std::process::Command;

use anari_library_caveray::scene::StructuredVolume;
use glam::{DVec3, Mat4, Vec3};
use serde_json::Value;

use crate::common;

/// A fresh folder for `name`'s files.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `script` in folder `name` with the tests' Python (CAVERAY_PYTHON,
/// else target/pynari): the folder and the JSON object it printed, one
/// entry a file. None where there is no such Python (CI fails then).
pub fn written_by(tool: &str, script: &str, name: &str) -> Option<(PathBuf, Value)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = std::env::var_os("CAVERAY_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/pynari/bin/python"));
    if !python.exists() {
        common::missing(&format!(
            "{tool} in the tests' virtual environment (target/pynari, made by scripts/deps)"
        ));
        return None;
    }
    let dir = scratch(name);
    let run = Command::new(&python)
        .arg("-c")
        .arg(script)
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{tool}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    Some((dir, serde_json::from_slice(&run.stdout).unwrap()))
}

/// Asserts that file `name`'s brightest voxel is at the index `truth`
/// gives ("marker"), of its value ("value"), and that `transform` takes it
/// to within `within` of its world position ("world").
pub fn marker_lands(
    name: &str,
    volume: &StructuredVolume,
    transform: Mat4,
    truth: &Value,
    within: f64,
) {
    let (mut best, mut at) = (f32::NEG_INFINITY, 0);
    for i in 0..volume.voxels().len() {
        if volume.value(i) > best {
            (best, at) = (volume.value(i), i);
        }
    }
    let dims = volume.dims();
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    let index = Vec3::new(
        (at % nx) as f32,
        ((at / nx) % ny) as f32,
        (at / (nx * ny)) as f32,
    );
    let numbers = |key: &str| -> Vec<f64> {
        truth[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let marker = DVec3::from_slice(&numbers("marker")).as_vec3();
    assert_eq!(index, marker, "{name}: the marker's index");
    let value = truth["value"].as_f64().unwrap() as f32;
    assert!(
        (best - value).abs() <= 1e-3 * value.abs(),
        "{name}: marker value {best}, the writer's {value}"
    );
    let world = transform.transform_point3(index).as_dvec3();
    let want = DVec3::from_slice(&numbers("world"));
    assert!(
        world.distance(want) < within,
        "{name}: marker at {world}, the header puts it at {want}"
    );
}

/// Asserts that file `name`'s voxels of stored type `dtype` are held in
/// that type where the renderers sample it (8 and 16-bit integers, 32-bit
/// floats), not as a copy in 32-bit floats.
pub fn kept_in_its_type(name: &str, volume: &StructuredVolume, dtype: &str) {
    use anari_library_caveray::scene::Voxels;
    let held = match volume.voxels() {
        Voxels::U8(_) => "uint8",
        Voxels::U16(_) => "uint16",
        Voxels::I16(_) => "int16",
        Voxels::F32(_) => "float32",
    };
    let sampled = ["uint8", "uint16", "int16", "float32"];
    let want = if sampled.contains(&dtype) {
        dtype
    } else {
        "float32"
    };
    assert_eq!(held, want, "{name}: {dtype} voxels held as {held}");
}
