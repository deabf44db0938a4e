//! Materials: one module per subtype, each giving a surface its coloring
//! before the renderer's Blinn-Phong shading.

pub mod curvature;
pub mod matte;

pub use crate::render::iso::Coloring;
