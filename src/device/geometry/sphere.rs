//! ANARI's `sphere` geometry (ANARI_KHR_GEOMETRY_SPHERE): a sphere per
//! vertex, or per entry of `primitive.index`, of the vertex's radius or
//! the geometry's.

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_SPHERE, F32};
use crate::device::types::DataType as T;

use super::attributes::{self, shape_params};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::GEOMETRY,
    subtype: "sphere",
    description: "spheres: one per vertex, or per entry of primitive.index",
    extensions: &[EXT_SPHERE],
    params: &shape_params!(
        p(
            "vertex.radius",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "FLOAT32 per vertex (default: 'radius' for every sphere)",
        )
        .elements(&[T::FLOAT32]),
        p(
            "radius",
            F32,
            false,
            DefaultValue::Floats(&[0.01]),
            "every sphere's radius where vertex.radius is unset",
        ),
        p(
            "primitive.index",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "UINT32 per sphere: its vertex (default: every vertex)",
        )
        .elements(&[T::UINT32]),
    ),
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let mut holds = attributes::Holds::new();
    let positions = attributes::positions(r)?;
    let radii = attributes::vertex_radii(r, positions.len())?;
    let index = match attributes::indices(r, "primitive.index", T::UINT32)? {
        Some(i) => i,
        None => (0..positions.len() as u32).collect(),
    };
    let input = attributes::input(r, positions.len(), index.len(), &mut holds)?;
    let made =
        crate::scene::Shape::spheres(positions, radii, index, input).map_err(|e| e.to_string())?;
    super::made(made, holds, warn)
}
