//! `scripts/deps`, which both README commands run first, on a machine where
//! another process holds the package lock: it tries again, saying so, and
//! gives up with a message after a bounded number of tries. apt-get,
//! dpkg-query and id are stand-ins on PATH; nothing is installed.

use std::path::Path;
use std::process::{Command, Output};

/// Runs scripts/deps with stand-ins for apt-get (failing its first
/// `failures` calls as a held lock does), dpkg-query (nothing installed)
/// and id (root, so no sudo). Returns the output and apt-get's calls.
fn deps_with_busy_apt(name: &str, failures: u32, tries: u32) -> (Output, Vec<String>) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("apt-get.log");
    let count = dir.join("apt-get.count");
    let script = |file: &str, body: String| {
        let path = dir.join(file);
        std::fs::write(&path, format!("#!/bin/sh\n{body}")).unwrap();
        Command::new("chmod").arg("+x").arg(&path).status().unwrap();
    };
    script(
        "apt-get",
        format!(
            "echo \"$*\" >> '{log}'\nn=$(cat '{count}' 2>/dev/null || echo 0)\necho $((n + 1)) > '{count}'\n\
             if [ \"$n\" -lt {failures} ]; then\n  echo 'E: Could not get lock /var/lib/apt/lists/lock. It is held by process 4242 (apt-get)' >&2\n  exit 100\nfi\n",
            log = log.display(),
            count = count.display(),
        ),
    );
    script("dpkg-query", "exit 1\n".into());
    script("id", "echo 0\n".into());
    let path = format!(
        "{}:{}",
        dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let output = Command::new("bash")
        .arg("scripts/deps")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("PATH", path)
        .env("APT_TRIES", tries.to_string())
        .env("APT_RETRY_SECONDS", "0")
        .env("DEPS_PYTHON", "no")
        .output()
        .expect("bash runs scripts/deps");
    let calls = std::fs::read_to_string(&log)
        .unwrap_or_default()
        .lines()
        .map(str::to_owned)
        .collect();
    (output, calls)
}

#[test]
fn deps_waits_out_a_held_package_lock() {
    let (output, calls) = deps_with_busy_apt("deps_busy", 2, 6);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "scripts/deps failed:\n{stderr}");
    for n in ["(1 of 6)", "(2 of 6)"] {
        assert!(
            stderr.contains(&format!("apt-get update failed (is another process holding the package lock?); trying again in 0 s {n}")),
            "no retry {n} said:\n{stderr}"
        );
    }
    assert_eq!(calls.len(), 4, "three updates, then the install: {calls:?}");
    assert!(calls[..3].iter().all(|c| c.contains("update")), "{calls:?}");
    assert!(
        calls[3].contains("install") && calls[3].contains("valgrind"),
        "{calls:?}"
    );
    assert!(
        calls.iter().all(|c| c.contains("DPkg::Lock::Timeout=60")),
        "apt-get waits for the lock itself too: {calls:?}"
    );
}

#[test]
fn deps_gives_up_on_a_lock_that_stays_held() {
    let (output, calls) = deps_with_busy_apt("deps_stuck", 100, 3);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success(),
        "scripts/deps succeeded:\n{stderr}"
    );
    assert!(
        stderr.contains("apt-get update failed 3 times; if another package manager is running, let it finish and run this again"),
        "{stderr}"
    );
    assert_eq!(calls.len(), 3, "{calls:?}");
}
