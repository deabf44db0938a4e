//! ANARI's `quad` geometry (ANARI_KHR_GEOMETRY_QUAD): a soup of vertex
//! quadruples, or quads indexed by `primitive.index`; each is drawn as two
//! triangles (a, b, c) and (a, c, d), which keeps the host's primitive
//! number for per-primitive attributes and ids. Per-vertex attributes are
//! interpolated across each triangle, not bilinearly across the quad.

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_QUAD};
use crate::device::types::DataType as T;

use super::attributes::{self, shape_params};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::GEOMETRY,
    subtype: "quad",
    description: "quads: consecutive vertex quadruples, or indexed by primitive.index; drawn as two triangles each",
    extensions: &[EXT_QUAD],
    params: &shape_params!(
        attributes::VERTEX_NORMAL,
        p(
            "primitive.index",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "UINT32_VEC4 per quad: its vertices in order around it (default: vertices 4i to 4i+3)",
        )
        .elements(&[T::UINT32_VEC4]),
    ),
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let mut holds = attributes::Holds::new();
    let positions = attributes::positions(r)?;
    let corners = match attributes::indices(r, "primitive.index", T::UINT32_VEC4)? {
        Some(i) => i,
        None => (0..(positions.len() / 4 * 4) as u32).collect(),
    };
    let quads = corners.len() / 4;
    let mut triangles = Vec::with_capacity(2 * quads);
    let mut source = Vec::with_capacity(2 * quads);
    for (k, q) in corners.chunks_exact(4).enumerate() {
        triangles.push([q[0], q[1], q[2]]);
        triangles.push([q[0], q[2], q[3]]);
        source.extend([k as u32; 2]);
    }
    let normals = attributes::vec3s(r, "vertex.normal")?.map(Into::into);
    let input = attributes::input(r, positions.len(), quads, &mut holds)?;
    let made = crate::scene::Shape::triangles(
        positions,
        triangles,
        crate::scene::Kept::Listed(source),
        normals,
        input,
    )
    .map_err(|e| e.to_string())?;
    super::made(made, holds, warn)
}
