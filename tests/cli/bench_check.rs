//! `caveray bench check` refuses at once, before minutes of measuring,
//! where it has no baseline to compare with or the baseline is not one.
//! (The check itself runs in CI as `scripts/bench-check`; its rules are
//! unit-tested in the tool.)

use crate::common;

use common::caveray;

#[test]
fn a_missing_or_broken_baseline_is_an_error_before_anything_is_measured() {
    let dir = std::env::temp_dir().join(format!("caveray-bench-check-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("none.json");
    let broken = dir.join("broken.json");
    std::fs::write(&broken, "{\"figures\": 3}").unwrap();
    for (baseline, says) in [
        (&missing, "cannot read the baseline"),
        (&broken, "broken.json: invalid type"),
    ] {
        let result = caveray(&[
            "bench",
            "check",
            "--baseline",
            baseline.to_str().unwrap(),
            "--out",
            dir.join("out").to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains(says), "{stderr}");
        // Nothing was measured: no benchmark's report was written.
        assert!(!dir.join("out/stereo.json").exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
