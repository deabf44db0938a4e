//! An autostereoscopic-display host in C (tests/capi/c/autostereo_host.c): an
//! isosurface through ANARI_KHR_GEOMETRY_ISOSURFACE, seen through the
//! multiView camera; the panel image must be the host's own interleaving
//! of the views it renders one by one (exactly per subpixel, within 2
//! levels by passes), and misuse is reported by message and code.

use crate::common;

use common::c::{compile, describe, run_with, scratch, valgrind_available};

fn host(size: [&str; 2], valgrind: bool) -> String {
    let dir = scratch(&format!(
        "autostereo_host{}",
        if valgrind { "_valgrind" } else { "" }
    ));
    let program = dir.join("autostereo_host");
    compile(&["tests/capi/c/autostereo_host.c"], &program, false, true);
    let args: Vec<&std::path::Path> = size.iter().map(std::path::Path::new).collect();
    let output = run_with(&program, &args, valgrind, &[("CAVERAY_BACKEND", "cpu")]);
    let stdout = String::from_utf8_lossy(&output.stdout).to_string();
    assert!(
        output.status.success(),
        "autostereo_host: {}",
        describe(&output)
    );
    assert!(!stdout.contains("FAIL"), "{stdout}");
    assert!(stdout.contains("0 failed"), "{stdout}");
    stdout
}

#[test]
fn a_c_host_sees_the_panel_as_its_views_interleaved() {
    let out = host(["40", "24"], false);
    for line in out.lines().filter(|l| l.contains("differ")) {
        println!("autostereo_host: {line}");
    }
}

#[test]
fn the_autostereo_host_under_valgrind_leaks_nothing() {
    if !valgrind_available() {
        common::missing("valgrind is not installed");
        return;
    }
    host(["12", "8"], true);
}
