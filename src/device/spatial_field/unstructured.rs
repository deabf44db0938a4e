//! The `unstructured` field (ANARI_KHR_SPATIAL_FIELD_UNSTRUCTURED):
//! tetrahedra, hexahedra, wedges and pyramids by VTK's codes and vertex
//! order, values per vertex or per cell (scene/unstructured.rs samples
//! them). Hosts send `cell.type` as UINT8, or UINT32 where their binding
//! has no 8-bit integers (pynari); indices as UINT32 or UINT64.

use std::sync::Arc;

use glam::Vec3;

use super::reserve;
use crate::device::array::Array;
use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo};
use crate::device::types::words;
use crate::device::types::DataType as T;
use crate::scene::{
    check_counts, MeshInput, MeshValues, SpatialField, UnstructuredError, UnstructuredVolume,
};

const DATA_TYPES: &[T] = &[T::UFIXED8, T::FIXED16, T::UFIXED16, T::FLOAT32, T::FLOAT64];

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::SPATIAL_FIELD,
    subtype: "unstructured",
    description: "tetrahedra, hexahedra, wedges and pyramids (VTK codes and vertex order), values per vertex or per cell, sampled exactly in each cell",
    extensions: &["ANARI_KHR_SPATIAL_FIELD_UNSTRUCTURED"],
    params: &[
        p(
            "vertex.position",
            &[T::ARRAY1D],
            true,
            DefaultValue::None,
            "FLOAT32_VEC3 per vertex; positions past the last one the cells use are ignored",
        )
        .elements(&[T::FLOAT32_VEC3]),
        p(
            "vertex.data",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "a value per vertex (UFIXED8, FIXED16, UFIXED16, FLOAT32 or FLOAT64), interpolated by each cell's shape functions",
        )
        .elements(DATA_TYPES),
        p(
            "index",
            &[T::ARRAY1D],
            true,
            DefaultValue::None,
            "UINT32 or UINT64: the cells' vertices, cell after cell",
        )
        .elements(&[T::UINT32, T::UINT64]),
        p(
            "cell.index",
            &[T::ARRAY1D],
            true,
            DefaultValue::None,
            "UINT32 or UINT64 per cell: its first entry in index (a cell ends where the next begins)",
        )
        .elements(&[T::UINT32, T::UINT64]),
        p(
            "cell.type",
            &[T::ARRAY1D],
            true,
            DefaultValue::None,
            "UINT8 or UINT32 per cell, VTK's codes: 10 tetrahedron, 12 hexahedron, 13 wedge, 14 pyramid",
        )
        .elements(&[T::UINT8, T::UINT32]),
        p(
            "cell.data",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "a value per cell (as vertex.data), constant over it; vertex.data wins when both are set",
        )
        .elements(DATA_TYPES),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let need =
        |name: &str, kind: &str| format!("parameter '{name}' (ARRAY1D of {kind}) is required");
    let count = |name: &str| -> Result<Option<u64>, String> { r.array(name, |a| Ok(a.dims()[0])) };
    // Counts first: nothing is allocated for a mesh caveray cannot take.
    check_counts(
        count("vertex.position")?.unwrap_or(0),
        count("index")?.unwrap_or(0),
        count("cell.index")?.unwrap_or(0),
    )
    .map_err(|e| e.to_string())?;
    let positions = r
        .array("vertex.position", positions)?
        .ok_or_else(|| need("vertex.position", "FLOAT32_VEC3"))?;
    let n = positions.len();
    let index = r
        .array("index", |a| {
            indices(a, "index", |i, v| past_positions(i, v, n))
        })?
        .ok_or_else(|| need("index", "UINT32"))?;
    let len = index.len();
    let cell_index = r
        .array("cell.index", |a| {
            indices(a, "cell.index", |i, v| {
                UnstructuredError::CellPastIndex {
                    index: i,
                    value: v,
                    len,
                }
                .to_string()
            })
        })?
        .ok_or_else(|| need("cell.index", "UINT32"))?;
    let cell_type = r
        .array("cell.type", cell_types)?
        .ok_or_else(|| need("cell.type", "UINT8"))?;
    let vertex = r.array("vertex.data", |a| values(a, "vertex.data"))?;
    let cell = r.array("cell.data", |a| values(a, "cell.data"))?;
    let values = match (vertex, cell) {
        (Some(v), Some(_)) => {
            warn("both vertex.data and cell.data are set; vertex.data is sampled".into());
            MeshValues::PerVertex(v)
        }
        (Some(v), None) => MeshValues::PerVertex(v),
        (None, Some(c)) => MeshValues::PerCell(c),
        (None, None) => {
            return Err("an unstructured field needs 'vertex.data' or 'cell.data'".into());
        }
    };
    let mesh = UnstructuredVolume::new(
        MeshInput {
            positions,
            index,
            cell_index,
            cell_type,
        },
        values,
    )
    .map_err(|e| e.to_string())?;
    Ok(Some(State::ready(Arc::new(SpatialField::from(mesh)))))
}

fn past_positions(index: usize, value: u64, positions: usize) -> String {
    UnstructuredError::IndexPastPositions {
        index,
        value,
        positions,
    }
    .to_string()
}

fn positions(a: &Array) -> Result<Vec<Vec3>, String> {
    if a.element() != T::FLOAT32_VEC3 {
        return Err(format!(
            "'vertex.position' holds {}; it needs FLOAT32_VEC3",
            a.element()
        ));
    }
    let n = a.dims()[0] as usize;
    let mut out = reserve(n as u64, "vertex positions")?;
    out.extend(words::<12>(a.bytes()).take(n).map(|w| {
        let f = |k: usize| f32::from_ne_bytes([w[k], w[k + 1], w[k + 2], w[k + 3]]);
        Vec3::new(f(0), f(4), f(8))
    }));
    Ok(out)
}

/// UINT32 or UINT64 entries as u32; a UINT64 entry past u32 is past
/// whatever it indexes (`past` says so).
fn indices(a: &Array, name: &str, past: impl Fn(usize, u64) -> String) -> Result<Vec<u32>, String> {
    let n = a.dims()[0] as usize;
    let mut out = reserve(n as u64, name)?;
    match a.element() {
        T::UINT32 => out.extend(words::<4>(a.bytes()).take(n).map(u32::from_ne_bytes)),
        T::UINT64 => {
            for (i, w) in words::<8>(a.bytes()).take(n).enumerate() {
                let v = u64::from_ne_bytes(w);
                out.push(u32::try_from(v).map_err(|_| past(i, v))?);
            }
        }
        other => return Err(format!("'{name}' holds {other}; it needs UINT32 or UINT64")),
    }
    Ok(out)
}

fn cell_types(a: &Array) -> Result<Vec<u32>, String> {
    let n = a.dims()[0] as usize;
    let mut out = reserve(n as u64, "cell types")?;
    match a.element() {
        T::UINT8 => out.extend(a.bytes().iter().take(n).map(|&b| u32::from(b))),
        T::UINT32 => out.extend(words::<4>(a.bytes()).take(n).map(u32::from_ne_bytes)),
        other => {
            return Err(format!(
                "'cell.type' holds {other}; it needs UINT8 or UINT32"
            ))
        }
    }
    Ok(out)
}

/// A value array's entries, one per element.
fn values(a: &Array, name: &str) -> Result<Vec<f32>, String> {
    super::values(a, &format!("'{name}'"), a.dims()[0])
}
