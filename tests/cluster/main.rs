//! `caveray render` as an MPI job (built with `--features mpi`, run by
//! scripts/test): `mpirun --oversubscribe -np 4` shares the Cologne CAVE's
//! walls out over four ranks, which gather on rank 0 the same images the
//! single process renders, and the timings of each rank; or cuts the
//! volume into four bricks, one per rank, whose partial images are
//! composited by direct-send into the single process's image.

#![cfg(feature = "mpi")]

#[path = "../common/cts.rs"]
#[allow(dead_code)]
mod cts;

use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The tool with `args`, alone or as `n` ranks under `mpirun`; fails the
/// test if it fails.
fn caveray(launcher: Option<u32>, args: &[&str]) {
    let caveray = env!("CARGO_BIN_EXE_caveray");
    let mut command = match launcher {
        None => Command::new(caveray),
        Some(n) => {
            let mut c = Command::new("mpirun");
            c.args(["--oversubscribe", "-np", &n.to_string(), caveray]);
            c
        }
    };
    // Open MPI refuses to run as root unless told (containers, CI).
    let run = command
        .args(args)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .output()
        .unwrap_or_else(|e| {
            panic!("cannot start {launcher:?}: {e} (scripts/deps installs openmpi-bin)")
        });
    assert!(
        run.status.success(),
        "{launcher:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
}

fn config() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cave_configs/cologne_5wall.toml")
}

fn render(launcher: Option<u32>, out: &Path) {
    let config = config();
    caveray(
        launcher,
        &[
            "render",
            "--config",
            config.to_str().unwrap(),
            "--scale",
            "0.03",
            "--backend",
            "cpu",
            "--out",
            out.to_str().unwrap(),
        ],
    );
}

fn pixels(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8()
}

#[test]
fn four_ranks_render_the_cave_as_one_process_does() {
    let (one, four) = (scratch("mpi_one"), scratch("mpi_four"));
    render(None, &one);
    render(Some(4), &four);
    let mut images = 0;
    for entry in std::fs::read_dir(&one).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "png") {
            let name = path.file_name().unwrap();
            assert_eq!(
                pixels(&path),
                pixels(&four.join(name)),
                "{}",
                name.to_string_lossy()
            );
            images += 1;
        }
    }
    // Five walls, two eyes each, and a contact sheet per eye.
    assert_eq!(images, 12);

    let timings: serde_json::Value =
        serde_json::from_slice(&std::fs::read(four.join("timings.json")).unwrap()).unwrap();
    let cluster = &timings["cluster"];
    let ranks = cluster["ranks"].as_array().unwrap();
    assert_eq!(ranks.len(), 4, "{cluster}");
    let mut walls: Vec<String> = ranks
        .iter()
        .flat_map(|r| r["walls"].as_array().unwrap().iter())
        .map(|w| w.as_str().unwrap().to_string())
        .collect();
    walls.sort();
    assert_eq!(walls, ["ceiling", "floor", "front", "left", "right"]);
    let slowest = ranks
        .iter()
        .map(|r| r["render_ms"].as_f64().unwrap())
        .fold(0.0, f64::max);
    assert_eq!(cluster["frame_ms"].as_f64(), Some(slowest));
    assert!(ranks
        .iter()
        .all(|r| r["barrier_ms"].as_f64().unwrap() >= 0.0));
    // Every view is recorded once, in the rig's wall order.
    let views: Vec<(String, String)> = timings["views"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| {
            (
                v["wall"].as_str().unwrap().into(),
                v["eye"].as_str().unwrap().into(),
            )
        })
        .collect();
    let single: serde_json::Value =
        serde_json::from_slice(&std::fs::read(one.join("timings.json")).unwrap()).unwrap();
    let expected: Vec<(String, String)> = single["views"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| {
            (
                v["wall"].as_str().unwrap().into(),
                v["eye"].as_str().unwrap().into(),
            )
        })
        .collect();
    assert_eq!(views, expected);
    assert!(single.get("cluster").is_none());
}

#[test]
fn four_ranks_composite_their_bricks_into_the_single_image() {
    let (one, four) = (scratch("mpi_dp_one"), scratch("mpi_dp_four"));
    let config = config();
    let run = |launcher: Option<u32>, out: &Path, parts: &[&str]| {
        let mut args = vec![
            "render",
            "--config",
            config.to_str().unwrap(),
            "--scale",
            "0.04",
            "--backend",
            "cpu",
            "--volume",
            "phantom:48",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(parts);
        caveray(launcher, &args);
    };
    run(None, &one, &[]);
    run(Some(4), &four, &["--parts", "4"]);
    let mut compared = 0;
    for wall in ["front", "left", "right", "floor", "ceiling"] {
        for eye in ["left", "right"] {
            let name = format!("{wall}_{eye}.png");
            let (a, b) = (pixels(&one.join(&name)), pixels(&four.join(&name)));
            let (w, h) = a.dimensions();
            let (ssim, _) = cts::score(a.as_raw(), b.as_raw(), w as usize, h as usize);
            let largest = a
                .as_raw()
                .iter()
                .zip(b.as_raw())
                .map(|(x, y)| x.abs_diff(*y))
                .max();
            // Measured: SSIM 1.00000, at most one level apart.
            assert!(
                ssim >= 0.999 && largest <= Some(2),
                "{name}: SSIM {ssim}, {largest:?}"
            );
            compared += 1;
        }
    }
    assert_eq!(compared, 10);
    let timings: serde_json::Value =
        serde_json::from_slice(&std::fs::read(four.join("timings.json")).unwrap()).unwrap();
    let dp = &timings["data_parallel"];
    assert_eq!(dp["ranks"], 4, "{dp}");
    assert_eq!(dp["counts"], serde_json::json!([2, 2, 1]));
    // Each view: every rank's render and compositing time, and the bytes
    // it sent: three bands of its float partial image, and (but rank 0)
    // its composited band in 8 bits.
    let width = timings["views"][0]["width"].as_u64().unwrap();
    let height = timings["views"][0]["height"].as_u64().unwrap();
    let band = |r: u64| (height * (r + 1) / 4 - height * r / 4) * width;
    for cost in dp["costs"].as_array().unwrap() {
        assert_eq!(cost["render_ms"].as_array().unwrap().len(), 4, "{cost}");
        assert_eq!(cost["composite_ms"].as_array().unwrap().len(), 4, "{cost}");
        assert_eq!(cost["samples"].as_array().unwrap().len(), 4, "{cost}");
        let sent: Vec<u64> = cost["bytes_sent"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b.as_u64().unwrap())
            .collect();
        let expected: Vec<u64> = (0..4)
            .map(|r| {
                let others: u64 = (0..4).filter(|&j| j != r).map(|j| 16 * band(j)).sum();
                others + if r == 0 { 0 } else { 4 * band(r) }
            })
            .collect();
        assert_eq!(sent, expected);
    }
}

/// `bench cave-stereo` along the shipped walk under `mpirun -np 2` (the
/// GPU's re-projection, on lavapipe here): each rank times its walls and
/// waits at a barrier every frame; rank 0's report holds every wall of
/// every frame, as one process's does, and each rank's times.
#[test]
fn two_ranks_time_the_cave_walk_frame_by_frame() {
    let dir = scratch("mpi_cave_stereo");
    let config = config();
    let json = |name: &str| dir.join(name);
    let run = |launcher: Option<u32>, out: &Path| -> serde_json::Value {
        caveray(
            launcher,
            &[
                "bench",
                "cave-stereo",
                "--config",
                config.to_str().unwrap(),
                "--scale",
                "0.02",
                "--frames",
                "2",
                "--volume",
                "phantom:24",
                "--json",
                out.to_str().unwrap(),
            ],
        );
        serde_json::from_slice(&std::fs::read(out).unwrap()).unwrap()
    };
    let one = run(None, &json("one.json"));
    let two = run(Some(2), &json("two.json"));
    // The walls of each frame and whether they see the volume are the
    // rig's geometry; which path the planner takes depends on timings.
    let seen = |r: &serde_json::Value| -> Vec<Vec<(String, bool)>> {
        r["timeline"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| {
                f["walls"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|w| {
                        (
                            w["wall"].as_str().unwrap().to_string(),
                            w["path"] != "not visible",
                        )
                    })
                    .collect()
            })
            .collect()
    };
    assert_eq!(seen(&two), seen(&one));
    assert_eq!(seen(&one).len(), 2);
    let cluster = &two["cluster"];
    let ranks = cluster["ranks"].as_array().unwrap();
    assert_eq!(ranks.len(), 2);
    for r in ranks {
        assert_eq!(r["render_ms"].as_array().unwrap().len(), 2, "{r}");
        assert_eq!(r["barrier_ms"].as_array().unwrap().len(), 2, "{r}");
    }
    let frame_ms: Vec<f64> = cluster["frame_ms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (i, ms) in frame_ms.iter().enumerate() {
        let slowest = ranks
            .iter()
            .map(|r| r["render_ms"][i].as_f64().unwrap())
            .fold(0.0, f64::max);
        assert_eq!(*ms, slowest);
    }
    assert!(one.get("cluster").is_none());
}
