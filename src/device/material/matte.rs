//! ANARI's `matte` material (ANARI_KHR_MATERIAL_MATTE): one color, a
//! geometry attribute named as the color (`color`, `attribute0..3`), or a
//! sampler of one; `opacity` likewise, as `alphaMode` says: ignored (`opaque`),
//! composited in depth order (`blend`), or a cutoff (`mask`).

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_MATTE};
use crate::device::types::DataType as T;
use glam::Vec3;

use super::MaterialModel;
use crate::render::iso::Coloring;
use crate::scene::SurfaceMaterial;

const DEFAULT_COLOR: Vec3 = Vec3::splat(0.8);

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::MATERIAL,
    subtype: "matte",
    description: "one color (linear RGB), lit by the renderer's shading",
    extensions: &[EXT_MATTE],
    params: &[
        p(
            "color",
            super::COLOR_TYPES,
            false,
            DefaultValue::Floats(&[0.8, 0.8, 0.8]),
            "the surface's color, linear RGB in [0, 1] (a fourth component is ignored), the name of the geometry attribute that colors it (color, attribute0 to attribute3), or a sampler (its x, y, z); an isosurface, having no attributes, shows the default color for the last two",
        ),
        super::OPACITY,
        super::ALPHA_MODE,
        super::ALPHA_CUTOFF,
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let (color, color_sampler, flat) = super::color(r, "color", DEFAULT_COLOR, warn)?;
    let (opacity, opacity_sampler, alpha) = super::opacity_and_alpha(r, warn)?;
    Ok(Some(State::ready(MaterialModel {
        color_sampler,
        opacity_sampler,
        // An isosurface has no attributes: a named one is the default color.
        coloring: Coloring::Flat(flat),
        surface: Some(SurfaceMaterial {
            color,
            opacity,
            alpha,
            pbr: None,
        }),
    })))
}
