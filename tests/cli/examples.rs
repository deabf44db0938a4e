//! The Rust examples write into their own folders under out/examples/, so
//! running one never overwrites the demo's images.

use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every example's source and name.
fn examples() -> Vec<(String, String)> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(root().join("examples")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "rs") {
            let name = path.file_stem().unwrap().to_string_lossy().into_owned();
            out.push((name, std::fs::read_to_string(&path).unwrap()));
        }
    }
    assert!(out.len() >= 5, "examples/ holds the Rust examples");
    out
}

/// An example names its output folder once; every path it writes is
/// built from that name.
#[test]
fn every_example_writes_under_its_own_folder() {
    for (name, source) in examples() {
        let code: String = source
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        let own = format!("\"out/examples/{name}\"");
        for (at, _) in code.match_indices("\"out") {
            assert!(
                code[at..].starts_with(&own),
                "examples/{name}.rs writes to {} instead of out/examples/{name}",
                code[at..].split_whitespace().next().unwrap_or("")
            );
        }
        if code.contains("write_png") || code.contains("create_dir_all") {
            assert!(
                code.contains(&own),
                "examples/{name}.rs names no output folder"
            );
        }
    }
}
