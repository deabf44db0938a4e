//! ANARI's `isosurface` geometry (ANARI_KHR_GEOMETRY_ISOSURFACE): where a
//! spatial field takes one of the iso-values, ray cast (first crossing,
//! secant refinement) rather than meshed, so the surface is as smooth as
//! the field's filter. docs/autostereo.md has the caster.

use crate::device::object::{ObjectRef, State};
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_ISOSURFACE};
use crate::device::types::DataType as T;
use crate::render::iso::IsoFilter;

/// Iso-values one geometry may hold: each is a cast of its own.
pub const MAX_ISOVALUES: usize = 16;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::GEOMETRY,
    subtype: "isosurface",
    description: "where a spatial field equals an iso-value: the first crossing along each ray, refined by secant steps",
    extensions: &[EXT_ISOSURFACE],
    params: &[
        p(
            "field",
            &[T::SPATIAL_FIELD],
            true,
            DefaultValue::None,
            "the spatial field whose level sets are drawn",
        ),
        p(
            "isovalue",
            &[T::FLOAT32, T::ARRAY1D],
            true,
            DefaultValue::None,
            "one iso-value, or an ARRAY1D of FLOAT32 (up to 16; the nearest surface shows)",
        )
        .elements(&[T::FLOAT32]),
        p(
            "caveray.filter",
            &[T::STRING],
            false,
            DefaultValue::Text("trilinear"),
            "trilinear (the field's own values) or tricubic (the cubic B-spline: smooth normals and curvature, the data slightly smoothed)",
        )
        .names(&IsoFilter::NAMES),
    ],
    commit: Some(commit),
};

/// An isosurface geometry after commit. The field is resolved when a
/// frame renders, so a field committed later is the one drawn.
#[derive(Clone)]
pub struct IsoGeometry {
    pub field: ObjectRef,
    pub isovalues: Vec<f32>,
    pub filter: IsoFilter,
}

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let field = r
        .object("field")
        .ok_or("parameter 'field' (SPATIAL_FIELD) is required")?
        .clone();
    let isovalues = match r.array_of("isovalue", T::FLOAT32, |a| Ok(a.f32s()))? {
        Some(values) => values,
        None => vec![r.f32("isovalue")?],
    };
    if isovalues.is_empty() {
        return Err("'isovalue' array is empty".into());
    }
    if isovalues.len() > MAX_ISOVALUES {
        return Err(format!(
            "{} iso-values; one isosurface geometry holds up to {MAX_ISOVALUES}",
            isovalues.len()
        ));
    }
    if let Some((i, v)) = isovalues.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(format!("isovalue[{i}] is {v}; iso-values must be finite"));
    }
    // Unknown enumeration values fall back to the default (the spec's rule).
    let filter = match r.string("caveray.filter").map(str::parse::<IsoFilter>) {
        Some(Ok(f)) => f,
        None => IsoFilter::Trilinear,
        Some(Err(e)) => {
            warn(format!("caveray.filter: {e}; filtering is trilinear"));
            IsoFilter::Trilinear
        }
    };
    Ok(Some(State::ready(super::GeometryModel::Iso(IsoGeometry {
        field,
        isovalues,
        filter,
    }))))
}
