//! A tracked-display host (tests/capi/c/deadline_host.c) drives frames with a
//! deadline at a fixed rate while the camera moves, then stands still:
//! every frame is ready with the newest complete image warped to its
//! camera (quad, grid), the first one with the background, and a
//! still camera soon gets its own image; a warp too slow for the deadline
//! gives way to a faster one. How long the host waited is measured and
//! printed against the deadline, never asserted.

use crate::common;

use common::c::{compile, describe, run_with, scratch, valgrind_available};

/// Runs the host (deadline and period in ms) on the CPU backend; returns
/// its summary line.
fn host(
    warp: &str,
    deadline: &str,
    period: &str,
    frames: &str,
    size: &str,
    valgrind: bool,
) -> String {
    host_on("cpu", warp, [deadline, period, frames, size], valgrind)
}

fn host_on(
    backend: &str,
    warp: &str,
    [deadline, period, frames, size]: [&str; 4],
    valgrind: bool,
) -> String {
    let dir = scratch(&format!(
        "deadline_{warp}_{deadline}_{backend}{}",
        if valgrind { "_valgrind" } else { "" }
    ));
    let program = dir.join("deadline_host");
    compile(&["tests/capi/c/deadline_host.c"], &program, false, true);
    let args = [deadline, warp, period, frames, size];
    let args: Vec<&std::path::Path> = args.iter().map(std::path::Path::new).collect();
    let output = run_with(&program, &args, valgrind, &[("CAVERAY_BACKEND", backend)]);
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
    println!("deadline_host {warp} on {backend} ({size}^2, a frame every {period} ms): {summary}");
    summary
}

/// The number after `word` in the summary.
fn count(summary: &str, word: &str) -> u32 {
    summary
        .split_whitespace()
        .skip_while(|w| *w != word)
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no '{word}' in {summary}"))
}

#[test]
fn deadline_frames_are_ready_with_the_newest_image_warped_by_each_mode() {
    // 30 Hz with 25 ms deadlines: room for the cheap warps in a debug
    // build on a busy machine (README has 90 Hz in a release build). The
    // layers warp on the CPU takes longer: it gives way (below);
    // device_deadline.rs shows it through the device model.
    for warp in ["quad", "grid"] {
        let summary = host(warp, "25", "33.3", "30", "64", false);
        let warped = count(&summary, "warped");
        assert!(
            warped >= 5,
            "{warp}: only {warped} frames warped: {summary}"
        );
    }
}

#[test]
fn a_warp_too_slow_for_the_deadline_gives_way_to_a_faster_one() {
    // The layers warp cannot be done in a millisecond here: after its first
    // try, quad (or, where even that is too slow, none) shows the image.
    let summary = host("layers", "1", "11.1", "30", "64", false);
    let faster = count(&summary, "quad") + count(&summary, "none");
    assert!(faster >= 10, "the slow warp did not give way: {summary}");
}

#[test]
fn gpu_warps_show_the_newest_image_by_the_deadline() {
    // The GPU (lavapipe here) opens and compiles its warps in the
    // background while the CPU warps; then the GPU's warps, each waited
    // for until the deadline only, show the images. Enough frames for the
    // first full render on lavapipe (about 5 s) and many warps after it;
    // the waits are printed, not asserted.
    let summary = host_on("gpu", "grid", ["8", "11.1", "700", "64"], false);
    let warped = count(&summary, "warped");
    assert!(warped >= 5, "only {warped} frames warped: {summary}");
}

#[test]
fn deadline_frames_under_valgrind_leak_nothing() {
    if !valgrind_available() {
        common::missing("valgrind is not installed");
        return;
    }
    host("layers", "8", "11.1", "4", "24", true);
}
