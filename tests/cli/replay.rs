//! `caveray replay` end to end on a tiny run: both shipped head paths, a
//! headset and a wall view, every refresh in the JSON, an SVG trace and a
//! strip a path and view, every warp better than the stale image on the
//! step; bad arguments are one-line usage errors (exit 2).

use crate::common;

use common::caveray;
use serde_json::Value;

#[test]
fn both_shipped_paths_replay_for_a_headset_and_a_wall() {
    let dir = std::env::temp_dir().join(format!("caveray-replay-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let json = dir.join("replay.json");
    let result = caveray(&[
        "replay",
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
        "hmd,front",
        "--backend",
        "cpu",
        "--json",
        json.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        result.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&result.stderr)
    );
    assert!(stdout.contains("mean DSSIM"), "{stdout}");
    let report: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["modes"].as_array().unwrap().len(), 4);
    let runs = report["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 4, "two paths x two views");
    for run in runs {
        let name = format!(
            "{}_{}",
            run["path"].as_str().unwrap(),
            run["view"].as_str().unwrap()
        );
        assert_eq!(run["size"], serde_json::json!([40, 40]), "{name}");
        assert_eq!(
            run["refreshes"].as_array().unwrap().len(),
            60,
            "{name}: 1 s at 60 Hz"
        );
        assert!(run["images"].as_u64().unwrap() >= 2, "{name}: new images");
        for ext in ["svg", "png"] {
            let file = dir.join(format!("{name}.{ext}"));
            assert!(file.is_file(), "{} missing", file.display());
        }
        if run["path"] == "step_1s" {
            let mean = |i: usize| run["modes"][i]["mean_dssim"].as_f64().unwrap();
            for i in 1..4 {
                assert!(
                    mean(i) < mean(0),
                    "{name}: warp {i} {} vs none {}",
                    mean(i),
                    mean(0)
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_replay_arguments_are_usage_errors() {
    for (args, want) in [
        (vec!["--view", "attic"], "the rig has no such wall"),
        (vec!["--warp", "bent"], "unknown warp 'bent'"),
        (vec!["--layers", "9"], "--layers must be 1 to 8"),
        (vec!["--hz", "0"], "display rate must be 1 to 1000 Hz"),
        (vec!["--render-ms=-3"], "simulated render time"),
        (vec!["--warp-ms", "50"], "less than a refresh"),
        (vec!["--grid-spacing", "0"], "grid spacing must be 1 to 256"),
        (vec!["--path", "nowhere.toml"], "nowhere.toml"),
        (vec!["--volume-size=-1"], "expected a finite number > 0"),
    ] {
        let mut all = vec!["replay", "--volume", "phantom:8"];
        all.extend(args.iter().copied());
        let result = caveray(&all);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(want), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
    }
}
