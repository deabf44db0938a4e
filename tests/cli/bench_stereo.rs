//! `caveray bench stereo` end to end on a tiny setup: every measurement
//! Buchacher & Erdt report is in the JSON, the plot and heat maps are written,
//! and bad arguments are one-line errors.

use crate::common;

use common::caveray;
use serde_json::Value;

#[test]
fn the_paper_protocol_runs_and_reports_everything() {
    let dir = std::env::temp_dir().join(format!("caveray-bench-stereo-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let json = dir.join("stereo.json");
    let result = caveray(&[
        "bench",
        "stereo",
        "--volume",
        "phantom:32,marschner-lobb:24",
        "--size",
        "48",
        "--steps",
        "3",
        "--layers",
        "8",
        "--shading",
        "none,directional:1",
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
    assert_eq!(report["layers"], 8);
    assert_eq!(report["layer_bytes"], 48 * 48 * 8 * 8);
    // h from the planner: the 1 m sphere spans 7 pixels at 48 pixels wide.
    assert!((report["sphere_span_px"].as_f64().unwrap() - 7.0).abs() < 1e-9);
    let datasets = report["datasets"].as_array().unwrap();
    assert_eq!(datasets.len(), 2);
    for d in datasets {
        let runs = d["runs"].as_array().unwrap();
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[1]["extra_samples_per_sample"], 4);
        for r in runs {
            let f = |k: &str| r[k].as_f64().unwrap();
            for k in [
                "t_l_ms",
                "t_r_ms",
                "t_lr_ms",
                "composite_ms",
                "composite_every_offset_ms",
                "clear_ms",
            ] {
                assert!(f(k) > 0.0, "{k} in {r}");
            }
            let v = 1.0 - (f("t_lr_ms") - f("t_l_ms")) / f("t_r_ms");
            assert!((f("speedup_v") - v).abs() < 1e-12);
            assert!(
                f("dssim_mean") <= f("dssim_max") && f("dssim_max") < 0.05,
                "{r}"
            );
            assert_eq!(r["views"]["dssim"].as_array().unwrap().len(), 3);
        }
        let heatmap = dir.join(d["heatmap"].as_str().unwrap());
        let image = image::open(&heatmap).unwrap();
        // Two-pass, re-projected and the heat map, 8 pixels apart.
        assert_eq!((image.width(), image.height()), (3 * 48 + 2 * 8, 48));
    }
    let svg = std::fs::read_to_string(dir.join("stereo.svg")).unwrap();
    assert_eq!(svg.matches("<polyline").count(), 2);
    assert!(
        stdout.contains("V %") && stdout.contains("phantom:32"),
        "{stdout}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_arguments_are_one_line_errors() {
    for (args, needle) in [
        (vec!["--layers", "1"], "--layers >= 2"),
        (vec!["--size", "4"], "--size >= 8"),
        (vec!["--shading", "phong"], "unknown shading mode"),
        (
            vec!["--layer-format", "rgb"],
            "[possible values: rgba16f, rgba32f]",
        ),
        (
            vec!["--volume", "phantom:24,phantom:1"],
            "must be a whole number in 2..=1024",
        ),
    ] {
        let mut all = vec![
            "bench",
            "stereo",
            "--json",
            "/tmp/caveray-never.json",
            "--steps",
            "1",
        ];
        all.extend_from_slice(&args);
        let result = caveray(&all);
        let err = String::from_utf8(result.stderr).unwrap();
        assert_eq!(result.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.starts_with("caveray: ") && err.contains(needle),
            "{args:?}: {err}"
        );
    }
}
