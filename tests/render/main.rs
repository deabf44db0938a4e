//! The renderers, GPU and CPU reference: known answers, the GPU held to
//! the CPU, several volumes, empty-space skipping, filtered sampling,
//! surfaces beside volumes, isosurfaces and multi-view display images.

#[path = "../common/mod.rs"]
mod common;

mod amr;
mod autostereo;
mod bricks;
mod empty_space;
mod errors;
mod fast_path;
mod filtered_sampling;
mod hit_channels;
mod isosurface;
mod known_answers;
mod nanovdb;
mod out_of_core;
mod progress;
mod ray_casting;
mod several_volumes;
mod surfaces;
mod unstructured;
