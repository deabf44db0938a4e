//! Views made from another view's image: the re-projection stereo planner
//! and its GPU path against two-pass rendering, and the image warps.

#[path = "../common/mod.rs"]
mod common;

mod plan;
mod reprojection;
mod warp;
mod warp_gpu;
