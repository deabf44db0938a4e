//! `caveray render --parts N` in one process: the volume cut into bricks
//! (a grid's voxels, or a mesh's cells over its lattice), each brick's
//! samples ray cast on their own and the partial images composited front
//! to back, make the image one renderer makes of the whole, on the CPU and
//! on the GPU, whichever way the cuts lie.

use crate::common;

use common::{caveray, cts};

use std::path::{Path, PathBuf};

use serde_json::Value;

fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caveray-parts-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn render(out: &Path, volume: &str, extra: &[&str]) -> Value {
    let mut args = vec![
        "render",
        "--config",
        "cave_configs/cologne_5wall.toml",
        "--scale",
        "0.04",
        "--volume",
        volume,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let result = caveray(&args);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    serde_json::from_slice(&std::fs::read(out.join("timings.json")).unwrap()).unwrap()
}

/// (lowest SSIM, largest channel difference) over every wall and eye.
fn likeness(one: &Path, parts: &Path) -> (f64, u8) {
    let (mut lowest, mut largest) = (1.0f64, 0u8);
    for wall in ["front", "left", "right", "floor", "ceiling"] {
        for eye in ["left", "right"] {
            let name = format!("{wall}_{eye}.png");
            let a = image::open(one.join(&name)).unwrap().to_rgba8();
            let b = image::open(parts.join(&name)).unwrap().to_rgba8();
            let (w, h) = a.dimensions();
            let (ssim, _) = cts::score(a.as_raw(), b.as_raw(), w as usize, h as usize);
            lowest = lowest.min(ssim);
            let most = a
                .as_raw()
                .iter()
                .zip(b.as_raw())
                .map(|(x, y)| x.abs_diff(*y));
            largest = largest.max(most.max().unwrap_or(0));
        }
    }
    (lowest, largest)
}

fn compare(backend: &str, parts: &str, counts: [u64; 3]) {
    compare_volume("phantom:48", [47; 3], backend, parts, counts);
}

/// `volume`, of `cells` lattice cells a side, whole and in `parts`.
fn compare_volume(volume: &str, cells: [u64; 3], backend: &str, parts: &str, counts: [u64; 3]) {
    let name = std::path::Path::new(volume)
        .file_name()
        .unwrap()
        .to_string_lossy();
    let dir = scratch(&format!("{backend}-{parts}-{}", name.replace(':', "_")));
    let (one, split) = (dir.join("one"), dir.join("split"));
    render(&one, volume, &["--backend", backend]);
    let report = render(&split, volume, &["--backend", backend, "--parts", parts]);
    let (ssim, largest) = likeness(&one, &split);
    // Measured: SSIM 1.00000, at most one level apart (early termination
    // stops each brick's rays on its own).
    assert!(
        ssim >= 0.999 && largest <= 2,
        "{volume} on {backend}, {parts} bricks: SSIM {ssim}, {largest} levels"
    );
    let dp = &report["data_parallel"];
    let got: Vec<u64> = dp["counts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .collect();
    assert_eq!(got, counts, "{dp}");
    assert_eq!(dp["ranks"], 1);
    // The bricks own every lattice cell once.
    let owned: u64 = dp["bricks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            let o = &b["owned"];
            (0..3)
                .map(|a| o[1][a].as_u64().unwrap() - o[0][a].as_u64().unwrap())
                .product::<u64>()
        })
        .sum();
    assert_eq!(owned, cells.iter().product::<u64>());
    // Each brick holds what it stores: a part of the whole, not all of it.
    let held: Vec<u64> = dp["bricks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["stored_bytes"].as_u64().unwrap())
        .collect();
    assert!(held.iter().all(|&b| b > 0), "{held:?}");
    // Per rendered view: each brick's render, the compositing time, and
    // no bytes sent by one process.
    let costs = dp["costs"].as_array().unwrap();
    let rendered = report["views"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|v| v.get("ms").is_some())
        .count();
    assert_eq!(costs.len(), rendered, "{dp}");
    for c in costs {
        assert_eq!(
            c["render_ms"].as_array().unwrap().len(),
            counts.iter().product::<u64>() as usize
        );
        assert_eq!(c["bytes_sent"], serde_json::json!([0]));
        assert_eq!(
            c["samples"].as_array().unwrap().len(),
            counts.iter().product::<u64>() as usize
        );
    }
    assert!(report["views"][0]["path"]
        .as_str()
        .is_some_and(|p| p.starts_with("data-parallel")));
}

#[test]
fn bricks_side_by_side_and_one_behind_another_composite_to_the_whole_on_the_cpu() {
    compare("cpu", "4", [1, 2, 2]);
    compare("cpu", "8", [2, 2, 2]);
}

/// A mesh is cut over its lattice: each brick holds the cells whose boxes
/// reach its stored box, and takes only the samples it owns.
#[test]
fn a_meshs_bricks_composite_to_the_whole_mesh() {
    compare_volume("tets:24", [23; 3], "cpu", "4", [1, 2, 2]);
}

/// An AMR field is cut over its lattice too: each brick holds the cells
/// whose tents reach its stored box.
#[test]
fn an_amr_fields_bricks_composite_to_the_whole_field() {
    compare_volume("amr:32", [32; 3], "cpu", "4", [1, 2, 2]);
}

/// A NanoVDB grid is cut over its voxels: each brick samples the tree
/// within its stored box.
#[test]
fn a_nanovdb_grids_bricks_composite_to_the_whole_grid() {
    let Some(written) = crate::common::nanovdb::grids() else {
        return;
    };
    let grid = &written.grids["fog"];
    let cells: [u64; 3] = std::array::from_fn(|a| {
        (grid["hi"][a].as_i64().unwrap() - grid["lo"][a].as_i64().unwrap()) as u64
    });
    compare_volume(
        written.file().to_str().unwrap(),
        cells,
        "cpu",
        "4",
        [2, 1, 2],
    );
}

#[test]
fn bricks_composite_to_the_whole_on_the_gpu() {
    compare("gpu", "8", [2, 2, 2]);
}

#[test]
fn parts_that_cannot_be_are_refused_in_one_line() {
    let out = scratch("refused");
    let refuse = |extra: &[&str], says: &str| {
        let mut args = vec![
            "render",
            "--config",
            "cave_configs/cologne_5wall.toml",
            "--scale",
            "0.02",
            "--backend",
            "cpu",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let result = caveray(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(says), "{stderr}");
    };
    refuse(
        &["--volume", "phantom:4", "--parts", "64"],
        "a grid of 4x4x4 vertices has too few cells for 64 bricks",
    );
    refuse(&["--parts", "0"], "at least one brick");
    refuse(
        &["--parts", "2", "--mesh", "0.4"],
        "every brick would draw the mesh over its part",
    );
    refuse(
        &["--parts", "2", "--stereo", "reprojection"],
        "re-projection stereo needs one renderer to see the whole volume",
    );
}
