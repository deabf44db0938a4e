//! Volume data and transfer functions as files, manifests and presets.

#[path = "../common/mod.rs"]
mod common;

mod dicom;
mod fixtures;
mod flash;
mod metaimage;
mod nanovdb;
mod nifti;
mod nrrd;
mod volumes;
mod vtk;
mod vtk_mesh;
