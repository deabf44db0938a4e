//! A tracked-display host (tests/c/deadline_host.c) drives frames with a
//! deadline at a fixed rate while the camera moves, then stands still:
//! every frame is ready with the newest complete image warped to its
//! camera (quad, grid, layers), the first one with the background, and a
//! still camera soon gets its own image. How long the host waited is
//! measured and printed against the deadline, never asserted.

mod common;

use common::c::{compile, describe, run_with, scratch, valgrind_available};

/// Runs the host; returns its summary line.
fn host(warp: &str, frames: &str, size: &str, valgrind: bool) -> String {
    let dir = scratch(&format!(
        "deadline_{warp}{}",
        if valgrind { "_valgrind" } else { "" }
    ));
    let program = dir.join("deadline_host");
    compile(&["tests/c/deadline_host.c"], &program, false, true);
    let args = ["8", warp, "11.1", frames, size];
    let args: Vec<&std::path::Path> = args.iter().map(std::path::Path::new).collect();
    let output = run_with(&program, &args, valgrind, &[("CAVERAY_BACKEND", "cpu")]);
    assert!(
        output.status.success(),
        "deadline_host {warp}: {}",
        describe(&output)
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    let summary = stdout
        .lines()
        .find(|l| l.starts_with("waits:"))
        .unwrap_or_else(|| panic!("no summary: {stdout}"))
        .to_string();
    println!("deadline_host {warp} ({size}^2, 90 Hz, deadline 8 ms): {summary}");
    summary
}

#[test]
fn deadline_frames_are_ready_with_the_newest_image_warped_by_each_mode() {
    for warp in ["quad", "grid", "layers"] {
        let summary = host(warp, "30", "96", false);
        let warped: u32 = summary
            .split_whitespace()
            .skip_while(|w| *w != "warped")
            .nth(1)
            .and_then(|n| n.parse().ok())
            .unwrap();
        assert!(
            warped >= 5,
            "{warp}: only {warped} frames warped: {summary}"
        );
    }
}

#[test]
fn deadline_frames_under_valgrind_leak_nothing() {
    if !valgrind_available() {
        common::missing("valgrind is not installed");
        return;
    }
    host("layers", "4", "24", true);
}
