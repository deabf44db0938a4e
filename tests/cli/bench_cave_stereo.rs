//! `caveray bench cave-stereo` end to end on a tiny rig-sized run: the
//! shipped head path by default, every wall and frame in the JSON with
//! its path and reason, the share of wall-frames re-projected, the cost
//! planner's path, estimate and error per wall-frame and its summary,
//! plots over time and the worst heat map; bad arguments and head paths are
//! one-line errors naming the file.

use crate::common;

use common::caveray;
use serde_json::Value;

#[test]
fn the_shipped_head_path_runs_on_every_wall_and_reports_everything() {
    let dir = std::env::temp_dir().join(format!("caveray-cave-stereo-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let json = dir.join("walk.json");
    let result = caveray(&[
        "bench",
        "cave-stereo",
        "--volume",
        "phantom:24",
        "--scale",
        "0.02",
        "--frames",
        "4",
        "--json",
        json.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let report: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["benchmark"], "cave-stereo");
    assert_eq!(report["path"], "cave_configs/head_paths/cologne_walk.toml");
    assert_eq!(report["duration_s"], 15.0);
    // Timed without Mesa's on-disk shader cache, and saying so.
    assert_eq!(report["renderer"]["backend"], "gpu");
    assert_eq!(
        report["renderer"]["shader_cache"], "disabled",
        "{}",
        report["renderer"]
    );
    let timeline = report["timeline"].as_array().unwrap();
    assert_eq!(timeline.len(), 4);
    assert_eq!(report["wall_frames"], 4 * 5);
    let (mut visible, mut reprojected, mut planned_two) = (0, 0, 0);
    let (mut planned_sum, mut t_l_sum, mut t_r_sum, mut estimated) = (0.0, 0.0, 0.0, 0);
    for frame in timeline {
        let walls = frame["walls"].as_array().unwrap();
        let names: Vec<&str> = walls.iter().map(|w| w["wall"].as_str().unwrap()).collect();
        assert_eq!(names, ["front", "left", "right", "ceiling", "floor"]);
        for w in walls {
            match w["path"].as_str().unwrap() {
                "reprojected" => {
                    reprojected += 1;
                    visible += 1;
                    let f = |k: &str| w[k].as_f64().unwrap();
                    for k in ["t_l_ms", "t_r_ms", "t_lr_ms"] {
                        assert!(f(k) > 0.0, "{k} in {w}");
                    }
                    let v = 1.0 - (f("t_lr_ms") - f("t_l_ms")) / f("t_r_ms");
                    assert!((f("speedup_v") - v).abs() < 1e-12);
                    assert!(f("dssim") < 0.05, "{w}");
                    assert!(w["layers"].as_u64().unwrap() >= 1);
                    assert!(f("composite_ms") > 0.0 && f("composite_ms") < f("t_lr_ms"));
                    // The planner's path is timed as that path: T_l+r, or
                    // both eyes' own passes.
                    let planned = match w["planned"].as_str().unwrap() {
                        "reprojected" => f("t_lr_ms"),
                        "two-pass" => {
                            planned_two += 1;
                            f("t_l_ms") + f("t_r_ms")
                        }
                        other => panic!("unknown planned path {other}"),
                    };
                    assert_eq!(f("t_planned_ms"), planned, "{w}");
                    // A wall the warm-up measured has an estimate, and
                    // its error.
                    if let Some(expected) = w["expected_ms"].as_f64() {
                        let error = f("t_planned_ms") / expected - 1.0;
                        assert!((f("estimate_error") - error).abs() < 1e-9, "{w}");
                        estimated += 1;
                    }
                    assert!(w["probe"].is_boolean());
                    planned_sum += planned;
                    t_l_sum += f("t_l_ms");
                    t_r_sum += f("t_r_ms");
                }
                "two-pass" => {
                    visible += 1;
                    assert!(w["reason"].is_string(), "{w}");
                }
                "not visible" => {}
                other => panic!("unknown path {other}"),
            }
        }
    }
    assert_eq!(report["visible_wall_frames"], visible);
    assert_eq!(report["reprojected_wall_frames"], reprojected);
    let planner = &report["planner"];
    assert_eq!(planner["planned_two_passes"], planned_two);
    assert!(estimated > 0);
    assert_eq!(planner["probe_after"], 120);
    assert_eq!(planner["first_probe"], 8);
    assert!(
        planner["estimate_error_mean"].as_f64().unwrap()
            <= planner["estimate_error_max"].as_f64().unwrap()
    );
    let v_planned = 1.0 - (planned_sum - t_l_sum) / t_r_sum;
    let reported = report["speedup_v_planned"].as_f64().unwrap();
    assert!(
        (reported - v_planned).abs() < 1e-9,
        "{reported} vs {v_planned}"
    );
    let share = report["reprojected_share"].as_f64().unwrap();
    assert!((share - f64::from(reprojected) / f64::from(visible)).abs() < 1e-12);
    // Every head pose of the walk re-projects every wall that sees the
    // volume, the side walls' radial lines included.
    assert_eq!(share, 1.0, "{}", report["fallbacks"]);
    let walls = report["walls"].as_array().unwrap();
    assert_eq!(walls.len(), 5);
    assert!(walls
        .iter()
        .any(|w| w["radial_share"].as_f64().unwrap() > 0.0));
    assert!(report["dssim_mean"].as_f64().unwrap() <= report["dssim_max"].as_f64().unwrap());
    for plot in ["walk_dssim.svg", "walk_speedup.svg"] {
        let svg = std::fs::read_to_string(dir.join(plot)).unwrap();
        assert_eq!(svg.matches("<polyline").count(), 5, "{plot}");
    }
    let heatmap = image::open(dir.join(report["heatmap"].as_str().unwrap())).unwrap();
    assert_eq!(heatmap.height(), 32);
    assert!(
        stdout.contains("visible wall-frames re-projected"),
        "{stdout}"
    );
    assert!(
        stdout.contains("planned (re-projection or two passes"),
        "{stdout}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_arguments_and_head_paths_are_one_line_errors() {
    let dir = std::env::temp_dir().join(format!("caveray-cave-paths-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let backwards = dir.join("backwards.toml");
    std::fs::write(
        &backwards,
        "units = \"m\"\n[[pose]]\nt = 1.0\nhead = [0, 0, 0]\n[[pose]]\nt = 0.5\nhead = [0, 0, 0]\n",
    )
    .unwrap();
    let empty = dir.join("empty.toml");
    std::fs::write(&empty, "units = \"mm\"\n").unwrap();
    let (backwards, empty) = (backwards.to_str().unwrap(), empty.to_str().unwrap());
    for (args, needle) in [
        (vec!["--frames", "0"], "--frames must be at least 1"),
        (vec!["--scale", "0"], "--scale must be in (0, 4]"),
        (vec!["--scale", "0.001"], "DSSIM needs 8x8 pixels"),
        (
            vec!["--path", "cave_configs/none.toml"],
            "none.toml: cannot read",
        ),
        (
            vec!["--path", backwards],
            "backwards.toml:6:5: pose[1].t: times must be finite and increasing",
        ),
        (vec!["--path", empty], "needs at least one [[pose]]"),
    ] {
        let mut all = vec!["bench", "cave-stereo", "--json", "/tmp/caveray-never.json"];
        all.extend_from_slice(&args);
        let result = caveray(&all);
        let err = String::from_utf8(result.stderr).unwrap();
        assert_eq!(result.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.starts_with("caveray: ") && err.contains(needle),
            "{args:?}: {err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
