//! Shared helpers for the integration tests.
#![allow(dead_code)]

pub mod c;
pub mod cts;
pub mod device;
pub mod iso;
pub mod nanovdb;
pub mod render;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use anari_library_caveray::cave::{HeadPose, Rig};
use glam::DVec3;

/// Deterministic SplitMix64, so every run samples the same poses.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let unit = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * unit
    }
}

/// The volume manifest of the project's shared data, beside the checkout.
pub fn shared_manifest() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/volumes/volumes.toml")
}

/// For a test whose input (`what`) is missing: CI installs everything, so
/// there the test fails; elsewhere it says why it cannot run, and the
/// caller returns.
pub fn missing(what: &str) {
    if std::env::var_os("CI").is_some() {
        panic!("{what}, but CI must have it (scripts/deps installs the tools; the data is in ../shared)");
    }
    eprintln!("not run here: {what} (CI fails on this)");
}

pub fn config_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cave_configs")
}

/// Whether the TOML file at `path` is a multi-view display (a top-level
/// `views`), not a rig.
pub fn is_display(path: &Path) -> bool {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    text.parse::<toml::Table>()
        .is_ok_and(|t| t.contains_key("views"))
}

/// Every shipped rig, by file stem (displays left out).
pub fn shipped_rigs() -> Vec<(String, Rig)> {
    let mut rigs: Vec<(String, Rig)> = std::fs::read_dir(config_dir())
        .expect("cave_configs exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml") && !is_display(p))
        .map(|p| {
            let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
            let rig = Rig::load(&p).unwrap_or_else(|e| panic!("{e}"));
            (stem, rig)
        })
        .collect();
    rigs.sort_by(|a, b| a.0.cmp(&b.0));
    rigs
}

pub fn rig(stem: &str) -> Rig {
    Rig::load(&config_dir().join(format!("{stem}.toml"))).unwrap_or_else(|e| panic!("{e}"))
}

/// Largest wall extent: the length scale for positional tolerances.
pub fn rig_scale(rig: &Rig) -> f64 {
    rig.walls
        .iter()
        .map(|w| w.screen.width().max(w.screen.height()))
        .fold(0.0, f64::max)
}

/// A head pose anywhere in the rig's tracked space, looking anywhere a
/// person plausibly looks.
pub fn random_head(rig: &Rig, rng: &mut Rng) -> HeadPose {
    let (min, max) = rig
        .viewer
        .tracked_space
        .expect("shipped rigs state their tracked space");
    let position = DVec3::new(
        rng.uniform(min.x, max.x),
        rng.uniform(min.y, max.y),
        rng.uniform(min.z, max.z),
    );
    let ypr = DVec3::new(
        rng.uniform(-180.0, 180.0),
        rng.uniform(-70.0, 70.0),
        rng.uniform(-35.0, 35.0),
    );
    rig.head_pose(Some(position), Some(ypr))
}

/// Runs the built `caveray` tool from the repository root.
pub fn caveray(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caveray"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("caveray runs")
}
