//! ANARI's `triangle` geometry (ANARI_KHR_GEOMETRY_TRIANGLE): a soup of
//! vertex triples, or triangles indexed by `primitive.index`.

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_TRIANGLE};
use crate::device::types::DataType as T;
use crate::scene::Kept;

use super::attributes::{self, shape_params};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::GEOMETRY,
    subtype: "triangle",
    description: "triangles: consecutive vertex triples, or indexed by primitive.index",
    extensions: &[EXT_TRIANGLE],
    params: &shape_params!(
        attributes::VERTEX_NORMAL,
        p(
            "primitive.index",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "UINT32_VEC3 per triangle: its vertices (default: vertices 3i, 3i+1, 3i+2)",
        )
        .elements(&[T::UINT32_VEC3]),
    ),
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    // Shared arrays are read where the host keeps them.
    let mut holds = attributes::Holds::new();
    let positions = attributes::shared_positions(r, &mut holds)?;
    let triangles = match attributes::shared(r, "primitive.index", T::UINT32_VEC3, &mut holds)? {
        Some(t) => t,
        None => (0..(positions.len() / 3) as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect::<Vec<_>>()
            .into(),
    };
    let kept = Kept::All(triangles.len());
    let normals = attributes::shared(r, "vertex.normal", T::FLOAT32_VEC3, &mut holds)?;
    let input = attributes::input(r, positions.len(), triangles.len(), &mut holds)?;
    let lent = triangles.lender().is_some();
    let made = crate::scene::Shape::triangles(positions, triangles, kept, normals, input)
        .map_err(|e| e.to_string())?;
    if let (true, Some(why)) = (lent, &made.dropped) {
        r.cost(format!(
            "'primitive.index' is copied without the triangles left out ({why})"
        ));
    }
    super::made(made, holds, warn)
}
