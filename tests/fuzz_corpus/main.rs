//! Replays the fuzzers' committed corpus (fuzz/corpus/<target>/) and every
//! input that once crashed caveray (fuzz/regressions/<target>/) through
//! the fuzz targets' own harness, on stable Rust: each must return. The
//! fuzzing itself (nightly, libFuzzer) is `scripts/fuzz`.

#[path = "../../fuzz/src/harness.rs"]
#[allow(dead_code)]
mod harness;

use std::path::Path;
use std::sync::mpsc::RecvTimeoutError;
use std::time::Duration;

/// How long one input may run: each takes milliseconds.
const LIMIT: Duration = Duration::from_secs(30);

type Target = fn(&[u8]);

const TARGETS: [(&str, Target); 14] = [
    ("rig", harness::rig),
    ("display", harness::display),
    ("paraview", harness::paraview),
    ("raw_manifest", harness::raw_manifest),
    ("capi", harness::capi),
    ("nifti", harness::nifti),
    ("nrrd", harness::nrrd),
    ("metaimage", harness::metaimage),
    ("vtk", harness::vtk),
    ("dicom", harness::dicom),
    ("vtk_mesh", harness::vtk_mesh),
    ("unstructured", harness::unstructured),
    ("amr", harness::amr),
    ("nanovdb", harness::nanovdb),
];

/// Every file under fuzz/<kind>/<target>/, sorted.
fn inputs(kind: &str, target: &str) -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz")
        .join(kind)
        .join(target);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    files.sort();
    files
}

#[test]
fn the_committed_corpus_and_every_past_crash_run_through_cleanly() {
    for (target, run) in TARGETS {
        let corpus = inputs("corpus", target);
        assert!(
            corpus.len() >= 10,
            "fuzz/corpus/{target} holds {} inputs; run scripts/fuzz to grow it",
            corpus.len()
        );
        let past = inputs("regressions", target);
        for file in corpus.iter().chain(&past) {
            let data = std::fs::read(file).unwrap();
            // Each input on a thread of its own, so that one that hangs is
            // named instead of stopping the test for good.
            let (done, finished) = std::sync::mpsc::channel();
            std::thread::spawn(move || {
                run(&data);
                let _ = done.send(());
            });
            let ran = finished.recv_timeout(LIMIT);
            assert!(
                !matches!(ran, Err(RecvTimeoutError::Timeout)),
                "{} did not return within {LIMIT:?}",
                file.display()
            );
            assert!(ran.is_ok(), "{} panicked", file.display());
        }
        eprintln!(
            "{target}: {} corpus inputs, {} past crashes",
            corpus.len(),
            past.len()
        );
    }
}
