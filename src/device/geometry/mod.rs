//! Geometries: one module per subtype. Surfaces of a field (`isosurface`)
//! are ray cast in the field; surfaces of primitives (`triangle`, `quad`,
//! `sphere`, `cylinder`, `cone`, `curve`) become a scene shape the
//! renderers trace through a BVH.

pub(crate) mod attributes;
pub mod cone;
pub mod curve;
pub mod cylinder;
pub mod isosurface;
pub mod quad;
pub mod sphere;
pub mod triangle;

use std::sync::Arc;

pub use isosurface::IsoGeometry;

use super::object::State;
use crate::scene::{Made, Shape};

/// A geometry after commit.
#[derive(Clone)]
pub enum GeometryModel {
    Iso(IsoGeometry),
    Shape(Arc<Shape>),
}

/// The state of a shape as made, holding the arrays it reads in place,
/// warning of what was dropped.
fn made(
    made: Made,
    holds: attributes::Holds,
    warn: &mut dyn FnMut(String),
) -> Result<Option<State>, String> {
    if let Some(why) = made.dropped {
        warn(format!("{why}: they would not show"));
    }
    Ok(Some(State::ready_holding(
        GeometryModel::Shape(Arc::new(made.shape)),
        holds,
    )))
}
