//! The ANARI device model through its Rust API: objects as hosts build
//! them, frames, stereo cameras and pairs, deadlines and isosurfaces.

#[path = "../common/mod.rs"]
mod common;

mod amr;
mod cts_volume;
mod deadline;
mod frames;
mod isosurface;
mod nanovdb;
mod params;
mod scene_graph;
mod stereo;
mod stereo_pairs;
mod surfaces;
mod volumes;
