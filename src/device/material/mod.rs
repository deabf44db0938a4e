//! Materials: one module per subtype, each giving a surface its color
//! before the renderer's shading.

pub mod curvature;
pub mod matte;

pub use crate::render::iso::Coloring;
use crate::scene::SurfaceMaterial;

/// A material after commit: how it colors an isosurface, and a surface of
/// primitives if it can (curvature needs a field's Hessian).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialModel {
    pub coloring: Coloring,
    pub surface: Option<SurfaceMaterial>,
}
