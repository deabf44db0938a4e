//! `caveray render` as an MPI job (built with `--features mpi`, run by
//! scripts/test under Open MPI and under MPICH): the Cologne CAVE's
//! walls shared out over four ranks, which gather on rank 0 the same images the
//! single process renders, and the timings of each rank; or cuts the
//! volume into four bricks, one per rank, whose partial images are
//! composited by direct-send into the single process's image; and a C
//! host whose four ranks each commit their slab of a volume to a device in
//! MPI mode maps the image one plain device makes of the whole.

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
            let mut c = mpirun(n, false);
            c.arg(caveray);
            c
        }
    };
    let run = command.args(args).output().unwrap_or_else(|e| {
        panic!("cannot start {launcher:?}: {e} (scripts/deps installs the MPIs CAVERAY_MPI names)")
    });
    assert!(
        run.status.success(),
        "{launcher:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
}

/// The launcher of the MPI this build is for (`CAVERAY_MPI`, which
/// scripts/test sets: `openmpi`, the default, or `mpich`) for `n` ranks
/// on this machine, passing LD_LIBRARY_PATH on where `library_path` says
/// (MPICH's launcher passes the whole environment).
fn mpirun(n: u32, library_path: bool) -> Command {
    let n = n.to_string();
    match std::env::var("CAVERAY_MPI").as_deref() {
        Ok("mpich") => {
            let mut c = Command::new("mpiexec.mpich");
            c.args(["-n", &n]);
            c
        }
        Ok("openmpi") | Err(_) => {
            let mut c = Command::new("mpirun.openmpi");
            c.args(["--oversubscribe", "-np", &n]);
            if library_path {
                c.args(["-x", "LD_LIBRARY_PATH"]);
            }
            // Open MPI refuses to run as root unless told (containers, CI).
            c.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
                .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
            c
        }
        Ok(other) => panic!("CAVERAY_MPI={other}: openmpi or mpich"),
    }
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
    assert_eq!(dp["counts"], serde_json::json!([1, 2, 2]));
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

/// `target/<profile>/deps`, where `cargo test --features mpi` built the
/// library with the feature.
fn lib_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().unwrap().to_path_buf();
    assert!(dir.join("libanari_library_caveray.so").exists());
    dir
}

/// tests/capi/c/mpi_bricks.c built against the library with the feature,
/// and the library path to run it with.
fn mpi_host(dir: &Path) -> (PathBuf, std::ffi::OsString) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let lib = lib_dir();
    let program = dir.join("mpi_bricks");
    let built = Command::new("cc")
        .current_dir(root)
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-g", "-Iinclude"])
        .arg("tests/capi/c/mpi_bricks.c")
        .arg("-o")
        .arg(&program)
        .arg(format!("-L{}", lib.display()))
        .arg("-lanari_library_caveray")
        .arg(format!("-Wl,-rpath,{}", lib.display()))
        .arg("-lm")
        .output()
        .expect("a C compiler");
    assert!(
        built.status.success(),
        "{}",
        String::from_utf8_lossy(&built.stderr)
    );
    // The library just built goes first: cargo puts target/<profile>,
    // which may hold one built without the feature, on the path.
    let mut path = std::ffi::OsString::from(&lib);
    if let Some(rest) = std::env::var_os("LD_LIBRARY_PATH") {
        path.push(":");
        path.push(rest);
    }
    (program, path)
}

/// Runs the host alone or under `mpirun -np N`; its output, after
/// checking that it succeeded.
fn run_host(
    (program, path): &(PathBuf, std::ffi::OsString),
    launcher: Option<u32>,
    args: &[&str],
) -> String {
    let mut command = match launcher {
        None => Command::new(program),
        Some(n) => {
            let mut c = mpirun(n, true);
            c.arg(program);
            c
        }
    };
    let out = command
        .args(args)
        .env("LD_LIBRARY_PATH", path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{launcher:?}: {stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

#[test]
fn a_c_host_on_four_ranks_maps_the_whole_volumes_image() {
    let dir = scratch("mpi_c_host");
    let host = mpi_host(&dir);
    let (program, path) = &host;
    let run = |launcher: Option<u32>, args: &[&str]| run_host(&host, launcher, args);
    let d = dir.to_str().unwrap();
    // Without their regions the bricks' bounds overlap by their aprons:
    // every rank refuses the frame, and none waits for another.
    let refused = mpirun(4, true)
        .arg(program)
        .args([d, "unowned"])
        .env("LD_LIBRARY_PATH", path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&refused.stdout);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success(), "{stdout}");
    assert_eq!(stdout.matches("FAILED").count(), 4, "{stdout}{stderr}");
    assert!(
        stderr.contains("the regions of ranks 0 and 1 overlap"),
        "{stderr}"
    );
    run(None, &[d, "whole"]);
    let said = run(Some(4), &[d]);
    // Every rank mapped the composited frame.
    assert_eq!(said.matches("mapped").count(), 4, "{said}");
    let whole = std::fs::read(dir.join("whole.rgba")).unwrap();
    let bricks = std::fs::read(dir.join("bricks.rgba")).unwrap();
    assert_eq!(whole.len(), 96 * 96 * 4);
    let (ssim, psnr) = cts::score(&whole, &bricks, 96, 96);
    let largest = whole.iter().zip(&bricks).map(|(a, b)| a.abs_diff(*b)).max();
    // The image is mostly volume: it must not be the background alone.
    let lit = whole
        .chunks_exact(4)
        .filter(|p| p[0] > 30 || p[1] > 30 || p[2] > 30)
        .count();
    assert!(lit > 96 * 96 / 2, "{lit} pixels show the volume");
    // Measured: SSIM 0.99981, 3 levels in 2 pixels. Each rank stops its
    // rays at 0.99 opacity on its own, so up to 1 % of the light behind an
    // almost opaque brick shows that one renderer would have cut.
    assert!(
        ssim >= 0.999 && largest <= Some(4),
        "SSIM {ssim}, PSNR {psnr} dB, largest difference {largest:?}"
    );
}

/// The same slabs as unstructured fields (each rank's cells, one cell of
/// apron beyond its inner faces, cut into tetrahedra): each rank samples
/// only its own box, so samples in the aprons are counted once, and the
/// composite is one process's image of the whole mesh.
#[test]
fn a_c_host_on_four_ranks_maps_the_whole_meshs_image() {
    let dir = scratch("mpi_c_host_cells");
    let host = mpi_host(&dir);
    let d = dir.to_str().unwrap();
    run_host(&host, None, &[d, "whole", "cells"]);
    let said = run_host(&host, Some(4), &[d, "ranks", "cells"]);
    assert_eq!(said.matches("mapped").count(), 4, "{said}");
    let whole = std::fs::read(dir.join("whole_cells.rgba")).unwrap();
    let parts = std::fs::read(dir.join("cells.rgba")).unwrap();
    assert_eq!(whole.len(), 96 * 96 * 4);
    let lit = whole
        .chunks_exact(4)
        .filter(|p| p[0] > 30 || p[1] > 30 || p[2] > 30)
        .count();
    assert!(lit > 96 * 96 / 2, "{lit} pixels show the mesh");
    let (ssim, psnr) = cts::score(&whole, &parts, 96, 96);
    let largest = whole.iter().zip(&parts).map(|(a, b)| a.abs_diff(*b)).max();
    eprintln!("four ranks' cells against one: SSIM {ssim}, PSNR {psnr} dB, largest {largest:?}");
    assert!(
        ssim >= 0.999 && largest <= Some(4),
        "SSIM {ssim}, PSNR {psnr} dB, largest difference {largest:?}"
    );
}

/// `replay` under `mpirun -np 2`: the views shared out over the ranks,
/// every displayed frame ending at the barrier on both (the one with fewer
/// views waits through its idle turns), and rank 0's report holding the
/// runs one process makes, in the same order, with simulated render times
/// so that they are equal to the last number.
#[test]
fn two_ranks_replay_the_views_in_step_with_one_process() {
    let dir = scratch("mpi_replay");
    let config = config();
    let run = |launcher: Option<u32>, name: &str| -> serde_json::Value {
        let json = dir.join(format!("{name}.json"));
        let out = dir.join(name);
        caveray(
            launcher,
            &[
                "replay",
                "--config",
                config.to_str().unwrap(),
                "--volume",
                "phantom:24",
                "--render-ms",
                "40",
                "--scale",
                "0.025",
                "--hz",
                "60",
                "--cells",
                "4",
                "--view",
                "hmd,front,left",
                "--backend",
                "cpu",
                "--json",
                json.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
        );
        serde_json::from_slice(&std::fs::read(json).unwrap()).unwrap()
    };
    let one = run(None, "one");
    let two = run(Some(2), "two");
    assert_eq!(two["runs"], one["runs"]);
    assert_eq!(
        one["runs"].as_array().unwrap().len(),
        6,
        "two paths x three views"
    );
    assert!(one.get("cluster").is_none());
    let ranks = two["cluster"].as_array().unwrap();
    assert_eq!(ranks.len(), 2);
    assert_eq!(ranks[0]["views"], serde_json::json!(["hmd", "left"]));
    assert_eq!(ranks[1]["views"], serde_json::json!(["front"]));
    // Two paths of 1 s at 60 Hz, two turns each (rank 1's second idle).
    for r in ranks {
        assert_eq!(r["frames"], 240, "{r}");
        assert!(r["barrier_max_ms"].as_f64().unwrap() >= r["barrier_mean_ms"].as_f64().unwrap());
    }
}
