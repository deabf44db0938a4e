//! `caveray bench autostereo` end to end on a tiny panel: one JSON row per
//! view count with the four methods' times, the evaluations that grow
//! with the views only for the naive method, and the share of subpixels
//! the passes and green's shared hit leave off the exact image; bad
//! arguments are usage errors.

use crate::common;

use common::caveray;
use serde_json::Value;

#[test]
fn rows_for_each_view_count_and_the_naive_cost_grows_with_them() {
    let dir = std::env::temp_dir().join(format!("caveray-autostereo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("auto.json");
    let result = caveray(&[
        "bench",
        "autostereo",
        "--volume",
        "phantom:24",
        "--views",
        "1,8,24",
        "--scale",
        "0.03",
        "--iso",
        "0.2",
        "--repeat",
        "1",
        "--json",
        json.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        result.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let report: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["resolution"], serde_json::json!([58, 36]));
    let rows = report["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for (row, views) in rows.iter().zip([1.0, 8.0, 24.0]) {
        assert_eq!(row["views"].as_f64(), Some(views));
        for key in [
            "naive_ms",
            "per_pixel_ms",
            "geometric_spectral_ms",
            "green_geometry_ms",
        ] {
            assert!(row[key].as_f64().unwrap() > 0.0, "{key}");
        }
        assert!((row["naive_views"].as_f64().unwrap() - views).abs() < 1e-9);
        // Three rays a pixel; the views differ a little in length.
        let per_pixel = row["per_pixel_views"].as_f64().unwrap();
        assert!((per_pixel - 3.0).abs() < 0.2);
        // The passes: green's ray in full, the others from near its hit
        // (on this tiny panel nearly every hit is near a silhouette).
        let passes = row["geometric_spectral_views"].as_f64().unwrap();
        assert!(passes < per_pixel, "{passes} vs {per_pixel}");
        assert!(row["geometric_spectral_differing"].as_f64().unwrap() < 0.05);
        // Green's rays alone; red and blue shade its hits, exactly where
        // they share green's eye (one view).
        let green = row["green_geometry_views"].as_f64().unwrap();
        assert!((green - 1.0).abs() < 0.1, "{green}");
        let off = row["green_geometry_differing"].as_f64().unwrap();
        if views == 1.0 {
            assert_eq!(off, 0.0);
        } else {
            assert!(off > 0.0 && off < 0.5, "{off}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_autostereo_arguments_are_usage_errors() {
    for (args, want) in [
        (vec!["--views", "0"], "--views must be 1 to 64"),
        (vec!["--scale", "2"], "--scale must be in (0, 1]"),
        (vec!["--iso", "3"], "--iso must be a fraction"),
        (vec!["--repeat", "0"], "--repeat must be 1 to 100"),
        (
            vec!["--config", "cave_configs/cologne_5wall.toml"],
            "unknown field",
        ),
    ] {
        let mut all = vec![
            "bench",
            "autostereo",
            "--volume",
            "phantom:8",
            "--json",
            "/tmp/x.json",
        ];
        all.extend(args.iter().copied());
        let result = caveray(&all);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(want), "{args:?}: {stderr}");
    }
}

#[test]
fn render_makes_a_displays_interleaved_image_and_its_views() {
    let dir = std::env::temp_dir().join(format!("caveray-display-{}", std::process::id()));
    let result = caveray(&[
        "render",
        "--config",
        "cave_configs/lenticular_8view.toml",
        "--volume",
        "phantom:24",
        "--scale",
        "0.03",
        "--iso",
        "0.2",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        result.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&result.stderr)
    );
    assert!(stdout.contains("8 views, 58x36 pixels"), "{stdout}");
    let interleaved = image::open(dir.join("display_interleaved.png")).unwrap();
    assert_eq!((interleaved.width(), interleaved.height()), (58, 36));
    let views = image::open(dir.join("display_views.png")).unwrap();
    // Four views a row, two rows, 4-pixel gaps.
    assert_eq!((views.width(), views.height()), (4 * 62 + 4, 2 * 40 + 4));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_gpu_backend_times_the_gpu_passes() {
    let dir = std::env::temp_dir().join(format!("caveray-autostereo-gpu-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("auto.json");
    let result = caveray(&[
        "bench",
        "autostereo",
        "--backend",
        "gpu",
        "--volume",
        "phantom:16",
        "--views",
        "1,8",
        "--scale",
        "0.02",
        "--iso",
        "0.2",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let report: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(
        report["timed_on"].as_str().unwrap().starts_with("GPU "),
        "{}",
        report["timed_on"]
    );
    for row in report["rows"].as_array().unwrap() {
        assert!(row["naive_views"].is_null(), "evaluations are the CPU's");
        assert!(row["per_pixel_ms"].as_f64().unwrap() >= 0.0);
        assert!(row["geometric_spectral_differing"].as_f64().unwrap() < 0.05);
        assert!(row["green_geometry_ms"].as_f64().unwrap() >= 0.0);
        assert!(row["green_geometry_views"].is_null());
        let off = row["green_geometry_differing"].as_f64().unwrap();
        if row["views"] == 1 {
            assert_eq!(off, 0.0);
        } else {
            assert!(off < 0.5, "{off}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Without --json a bench writes under out/bench/ of the folder it runs
/// in, which git ignores, and makes that folder.
#[test]
fn without_json_the_report_goes_to_out_bench() {
    let dir =
        std::env::temp_dir().join(format!("caveray-autostereo-default-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let config =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cave_configs/lenticular_8view.toml");
    let result = std::process::Command::new(env!("CARGO_BIN_EXE_caveray"))
        .args(["bench", "autostereo", "--config"])
        .arg(&config)
        .args([
            "--volume",
            "phantom:16",
            "--views",
            "2",
            "--scale",
            "0.02",
            "--repeat",
            "1",
        ])
        .current_dir(&dir)
        .output()
        .expect("caveray runs");
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let json = dir.join("out/bench/autostereo.json");
    let report: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["rows"].as_array().map(Vec::len), Some(1));
    std::fs::remove_dir_all(&dir).unwrap();
}
