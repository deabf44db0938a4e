//! Materials: one module per subtype, each giving a surface its color
//! before the renderer's shading.

pub mod curvature;
pub mod matte;

use super::object::ObjectRef;
pub use crate::render::iso::Coloring;
use crate::scene::SurfaceMaterial;

/// A material after commit: how it colors an isosurface, and a surface of
/// primitives if it can (curvature needs a field's Hessian).
#[derive(Clone)]
pub struct MaterialModel {
    pub coloring: Coloring,
    pub surface: Option<SurfaceMaterial>,
    /// The sampler `color` names: resolved when a frame renders, so that
    /// its own later commits show.
    pub color_sampler: Option<ObjectRef>,
}
