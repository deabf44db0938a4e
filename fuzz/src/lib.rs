//! The fuzz targets' harness (see harness.rs), shared with the replay
//! test in the main crate.
pub mod harness;
