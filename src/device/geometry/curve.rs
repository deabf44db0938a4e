//! ANARI's `curve` geometry (ANARI_KHR_GEOMETRY_CURVE): round linear
//! curves, a segment from each vertex of `primitive.index` (else from
//! every vertex but the last) to the next, of the radii at the two, so
//! that a polyline of them reads as one smooth tube.

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_CURVE, F32};
use crate::device::types::DataType as T;

use super::attributes::{self, shape_params};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::GEOMETRY,
    subtype: "curve",
    description: "round linear curves: a segment from each vertex of primitive.index to the next",
    extensions: &[EXT_CURVE],
    params: &shape_params!(
        p(
            "primitive.index",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "UINT32 per segment: its first vertex; the next is its second (default: every vertex but the last)",
        )
        .elements(&[T::UINT32]),
        p(
            "vertex.radius",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "FLOAT32 per vertex (default: 'radius')",
        )
        .elements(&[T::FLOAT32]),
        p(
            "radius",
            F32,
            false,
            DefaultValue::Floats(&[1.0]),
            "every vertex's radius where vertex.radius is unset",
        ),
    ),
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let mut holds = attributes::Holds::new();
    let positions = attributes::positions(r)?;
    let radii = attributes::vertex_radii(r, positions.len())?;
    let first = match attributes::indices(r, "primitive.index", T::UINT32)? {
        Some(i) => i,
        None => (0..positions.len().saturating_sub(1) as u32).collect(),
    };
    let input = attributes::input(r, positions.len(), first.len(), &mut holds)?;
    let made =
        crate::scene::Shape::curves(positions, radii, first, input).map_err(|e| e.to_string())?;
    super::made(made, holds, warn)
}
