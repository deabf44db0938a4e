//! caveray's `curvature` material: a surface colored by its mean
//! curvature from the field's Hessian (blue concave, white flat, orange
//! convex), the coloring that shows shape on a display without shadows.

use super::MaterialModel;
use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_CURVATURE, F32};
use crate::device::types::DataType as T;
use crate::render::iso::Coloring;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::MATERIAL,
    subtype: "curvature",
    description: "colored by mean curvature: blue concave, white flat, orange convex",
    extensions: &[EXT_CURVATURE],
    params: &[p(
        "radius",
        F32,
        true,
        DefaultValue::None,
        "the colors saturate at a curvature of 1/radius (world units): the radius of the roundest bumps of interest",
    )],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let radius = r.f32("radius")?;
    if !(radius.is_finite() && radius > 0.0) {
        return Err(format!("radius must be positive and finite, got {radius}"));
    }
    Ok(Some(State::ready(MaterialModel {
        color_sampler: None,
        opacity_sampler: None,
        coloring: Coloring::Curvature { radius },
        surface: None,
    })))
}
