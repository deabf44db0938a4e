//! Isosurface ray casting: the CPU reference on its own, and the GPU
//! held to it.

mod cpu;
mod gpu;
