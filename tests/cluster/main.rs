//! `caveray render` as an MPI job (built with `--features mpi`, run by
//! scripts/test): `mpirun --oversubscribe -np 4` shares the Cologne CAVE's
//! walls out over four ranks, which gather on rank 0 the same images the
//! single process renders, and the timings of each rank.

#![cfg(feature = "mpi")]

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
