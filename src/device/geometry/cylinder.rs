//! ANARI's `cylinder` geometry (ANARI_KHR_GEOMETRY_CYLINDER): a cylinder
//! between each pair of consecutive vertices, or each pair of
//! `primitive.index`, of `primitive.radius` or the geometry's `radius`,
//! closed by discs where `vertex.cap` (or, without it, `caps`) says.

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_CYLINDER, F32};
use crate::device::types::DataType as T;

use super::attributes::{self, shape_params};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::GEOMETRY,
    subtype: "cylinder",
    description: "cylinders: between consecutive vertex pairs, or pairs of primitive.index",
    extensions: &[EXT_CYLINDER],
    params: &shape_params!(
        p(
            "primitive.index",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "UINT32_VEC2 per cylinder: its two ends (default: vertices 2i, 2i+1)",
        )
        .elements(&[T::UINT32_VEC2]),
        p(
            "primitive.radius",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "FLOAT32 per cylinder (default: 'radius' for every one)",
        )
        .elements(&[T::FLOAT32]),
        p(
            "radius",
            F32,
            false,
            DefaultValue::Floats(&[1.0]),
            "every cylinder's radius where primitive.radius is unset",
        ),
        attributes::VERTEX_CAP,
        p(
            "caps",
            &[T::STRING],
            false,
            DefaultValue::Text("none"),
            "where vertex.cap is unset, which ends are closed by a disc: none, first, second or both",
        )
        .names(&attributes::CAPS),
    ),
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let mut holds = attributes::Holds::new();
    let positions = attributes::positions(r)?;
    let ends = attributes::pairs(r, positions.len())?;
    let radii = match attributes::f32s(r, "primitive.radius")? {
        Some(radii) if radii.len() < ends.len() => {
            return Err(format!(
                "primitive.radius has {} values for {} cylinders",
                radii.len(),
                ends.len()
            ))
        }
        Some(radii) => radii,
        None => vec![r.f32("radius")?; ends.len()],
    };
    let caps = attributes::end_caps(r, positions.len(), &ends, warn)?;
    let input = attributes::input(r, positions.len(), ends.len(), &mut holds)?;
    let made = crate::scene::Shape::cones(
        "cylinder",
        positions,
        ends,
        radii.iter().map(|&r| [r, r]).collect(),
        caps,
        input,
    )
    .map_err(|e| e.to_string())?;
    super::made(made, holds, warn)
}
