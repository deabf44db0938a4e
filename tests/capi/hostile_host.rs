//! A hostile host (tests/capi/c/hostile_host.c), one case a program run, on
//! the CPU backend and on the GPU (lavapipe here): completion callbacks
//! that release the device, call into it while the host releases it, or
//! wait on their own frame; a second host thread calling while a frame
//! renders; discards and releases in the middle of long isosurface,
//! panel and stereo renders, and of deadline frames; deadline frames
//! resized between renders. Each must pass its checks with no panic on
//! stderr; the cases that touch host memory also run under valgrind. How
//! long releases, discards and the other thread's calls took is printed,
//! never asserted.

use crate::common;

use common::c::{compile, describe, run_with, scratch, valgrind_available};

fn case(name: &str, backend: &str, valgrind: bool) {
    let dir = scratch(&format!(
        "hostile_{name}_{backend}{}",
        if valgrind { "_valgrind" } else { "" }
    ));
    let program = dir.join("hostile_host");
    compile(&["tests/capi/c/hostile_host.c"], &program, false, true);
    let output = run_with(
        &program,
        &[std::path::Path::new(name)],
        valgrind,
        &[("CAVERAY_BACKEND", backend)],
    );
    let (stdout, stderr) = (
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr),
    );
    for line in stdout.lines().filter(|l| l.starts_with("measured:")) {
        println!("{name} ({backend}): {line}");
    }
    assert!(
        output.status.success(),
        "hostile_host {name} ({backend}): {}",
        describe(&output)
    );
    assert!(
        !stderr.contains("panicked"),
        "hostile_host {name} ({backend}) printed a panic:\n{stderr}"
    );
}

fn both(name: &str) {
    case(name, "cpu", false);
    case(name, "gpu", false);
}

#[test]
fn a_completion_callback_may_release_the_device() {
    both("callback-release");
}

#[test]
fn a_callback_calling_in_while_the_host_releases_the_device_is_safe() {
    both("release-while-called");
}

#[test]
fn a_completion_callback_waiting_on_its_own_frame_is_refused_not_deadlocked() {
    both("callback-wait");
}

#[test]
fn a_second_host_thread_is_never_held_up_by_a_busy_frame() {
    both("second-thread");
}

#[test]
fn a_release_never_waits_for_a_deadline() {
    both("release-deadline");
}

#[test]
fn isosurface_panel_stereo_and_deadline_renders_stop_on_discard() {
    both("discard");
}

#[test]
fn a_resized_deadline_frame_always_renders() {
    both("resize-deadline");
}

#[test]
fn callbacks_into_the_device_leak_nothing_under_valgrind() {
    if !valgrind_available() {
        return common::missing("valgrind");
    }
    for name in ["callback-release", "release-while-called", "callback-wait"] {
        case(name, "cpu", true);
    }
}
