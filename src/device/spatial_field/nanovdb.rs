//! The `nanovdb` field (KHR_SPATIAL_FIELD_NANOVDB): one NanoVDB grid in
//! `data` as the NanoVDB library lays it out in memory, checked and read
//! as it is by scene/nanovdb.rs.

use std::sync::Arc;

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo};
use crate::device::types::DataType as T;
use crate::scene::{Filter, NanoVdbGrid, SpatialField};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::SPATIAL_FIELD,
    subtype: "nanovdb",
    description: "a NanoVDB grid (Float, Half, Fp4, Fp8 or Fp16 values) kept as sent and read through its own tree, placed by its index-to-world map",
    extensions: &["ANARI_KHR_SPATIAL_FIELD_NANOVDB"],
    params: &[
        p(
            "data",
            &[T::ARRAY1D],
            true,
            DefaultValue::None,
            "UINT8: one NanoVDB grid (layout version 32) exactly as the library holds it in memory",
        )
        .elements(&[T::UINT8]),
        p(
            "filter",
            &[T::STRING],
            false,
            DefaultValue::Text("linear"),
            "linear (trilinear between voxels) or nearest; cubic is not implemented and reads as linear, with a warning",
        )
        .names(&["linear", "nearest", "cubic"]),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let filter = match r.string("filter") {
        Some("nearest") => Filter::Nearest,
        Some("linear") | None => Filter::Linear,
        Some("cubic") => {
            warn("filter 'cubic' is not implemented for nanovdb fields; sampling is linear".into());
            Filter::Linear
        }
        Some(other) => {
            warn(format!(
                "filter '{other}' is not one of linear, nearest, cubic; sampling is linear"
            ));
            Filter::Linear
        }
    };
    let grid = r
        .array("data", |a| {
            if a.element() != T::UINT8 {
                return Err(format!("'data' holds {}; it needs UINT8", a.element()));
            }
            NanoVdbGrid::new(a.bytes(), filter).map_err(|e| format!("'data': {e}"))
        })?
        .ok_or("parameter 'data' (ARRAY1D of UINT8, a NanoVDB grid) is required")?;
    Ok(Some(State::ready(Arc::new(SpatialField::from(grid)))))
}
