//! The `caveray` tool end to end: its commands run as a user runs them.

#[path = "../common/mod.rs"]
mod common;

mod bench_autostereo;
mod bench_cave_stereo;
mod bench_check;
mod bench_gpu;
mod bench_stereo;
mod data_parallel;
mod deps;
mod examples;
mod inspect;
mod render;
mod replay;
mod rig_syntax;
mod view;
mod volumes;
