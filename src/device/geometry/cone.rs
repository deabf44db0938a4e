//! ANARI's `cone` geometry (ANARI_KHR_GEOMETRY_CONE): a cone between each
//! pair of consecutive vertices, or each pair of `primitive.index`, of
//! the radii at its two vertices, closed by discs where `vertex.cap` (or,
//! without it, `caps`) says.

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_CONE, F32};
use crate::device::types::DataType as T;

use super::attributes::{self, shape_params};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::GEOMETRY,
    subtype: "cone",
    description: "cones: between consecutive vertex pairs, or pairs of primitive.index",
    extensions: &[EXT_CONE],
    params: &shape_params!(
        p(
            "primitive.index",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "UINT32_VEC2 per cone: its two ends (default: vertices 2i, 2i+1)",
        )
        .elements(&[T::UINT32_VEC2]),
        p(
            "vertex.radius",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "FLOAT32 per vertex: the cone's radius at that end (default: 'radius')",
        )
        .elements(&[T::FLOAT32]),
        p(
            "radius",
            F32,
            false,
            DefaultValue::Floats(&[1.0]),
            "every end's radius where vertex.radius is unset",
        ),
        attributes::VERTEX_CAP,
        p(
            "caps",
            &[T::STRING],
            false,
            DefaultValue::Text("none"),
            "where vertex.cap is unset, which ends are closed: none, first, second or both",
        )
        .names(&attributes::CAPS),
    ),
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let mut holds = attributes::Holds::new();
    let positions = attributes::positions(r)?;
    let ends = attributes::pairs(r, positions.len())?;
    let radii = attributes::vertex_radii(r, positions.len())?;
    let caps = attributes::end_caps(r, positions.len(), &ends, warn)?;
    // Out-of-range ends are the shape's to report: read them as 0 here.
    let at = |v: u32| radii.get(v as usize).copied().unwrap_or(0.0);
    let cone_radii = ends.iter().map(|e| [at(e[0]), at(e[1])]).collect();
    let input = attributes::input(r, positions.len(), ends.len(), &mut holds)?;
    let made = crate::scene::Shape::cones("cone", positions, ends, cone_radii, caps, input)
        .map_err(|e| e.to_string())?;
    super::made(made, holds, warn)
}
