//! Volume data and transfer functions as files, manifests and presets.

#[path = "../common/mod.rs"]
mod common;

mod fixtures;
mod nifti;
mod nrrd;
mod volumes;
