//! ANARI's `matte` material (ANARI_KHR_MATERIAL_MATTE): one color, a
//! geometry attribute named as the color (`color`, `attribute0..3`), or a
//! sampler of one; `opacity` as `alphaMode` says: ignored (`opaque`),
//! composited in depth order (`blend`), or a cutoff (`mask`).

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_MATTE, F32};
use crate::device::types::DataType as T;
use glam::Vec3;

use super::MaterialModel;
use crate::render::iso::Coloring;
use crate::scene::{AlphaMode, ColorSource, SurfaceMaterial, ATTRIBUTE_NAMES};

const DEFAULT_COLOR: Vec3 = Vec3::splat(0.8);

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::MATERIAL,
    subtype: "matte",
    description: "one color (linear RGB), lit by the renderer's shading",
    extensions: &[EXT_MATTE],
    params: &[
        p(
            "color",
            &[T::FLOAT32_VEC3, T::FLOAT32_VEC4, T::STRING, T::SAMPLER],
            false,
            DefaultValue::Floats(&[0.8, 0.8, 0.8]),
            "the surface's color, linear RGB in [0, 1] (a fourth component is ignored), the name of the geometry attribute that colors it (color, attribute0 to attribute3), or a sampler (its x, y, z); an isosurface, having no attributes, shows the default color for the last two",
        ),
        p(
            "opacity",
            F32,
            false,
            DefaultValue::Floats(&[1.0]),
            "how much of what lies behind the surface it hides, under alphaMode blend or mask",
        )
        .range(0.0, 1.0),
        p(
            "alphaMode",
            &[T::STRING],
            false,
            DefaultValue::Text("opaque"),
            "opaque: opacity ignored; blend: composited with the volumes and surfaces behind in depth order (up to 8 translucent surfaces a ray); mask: opaque where opacity reaches alphaCutoff, else not drawn",
        )
        .names(&AlphaMode::NAMES),
        p(
            "alphaCutoff",
            F32,
            false,
            DefaultValue::Floats(&[0.5]),
            "the opacity from which a masked surface shows",
        )
        .range(0.0, 1.0),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let mut surface = SurfaceMaterial::default();
    let named = r.set("color").and_then(|v| v.string());
    let color_sampler = r.object("color").filter(|o| o.kind == T::SAMPLER).cloned();
    let flat = match named {
        _ if color_sampler.is_some() => DEFAULT_COLOR,
        Some(name) => {
            match ATTRIBUTE_NAMES.iter().position(|n| *n == name) {
                Some(slot) => surface.color = ColorSource::Attribute(slot),
                None => warn(format!(
                    "color names '{name}'; caveray colors by {}: drawn in the default color",
                    ATTRIBUTE_NAMES.join(", ")
                )),
            }
            DEFAULT_COLOR
        }
        None => {
            let color = match r.set("color").and_then(|v| v.f32s()) {
                Some(f) if f.len() == 4 => Vec3::from_slice(&f),
                _ => r.vec3("color")?,
            };
            if !color.is_finite() {
                return Err(format!("color {color} must be finite"));
            }
            let clamped = color.clamp(Vec3::ZERO, Vec3::ONE);
            if clamped != color {
                warn(format!("color {color} lies outside [0, 1]; clamped"));
            }
            surface.color = ColorSource::Constant(clamped);
            clamped
        }
    };
    let opacity = r.f32("opacity")?;
    if !opacity.is_finite() {
        return Err(format!("opacity {opacity} must be finite"));
    }
    surface.opacity = opacity.clamp(0.0, 1.0);
    if surface.opacity != opacity {
        warn(format!("opacity {opacity} lies outside [0, 1]; clamped"));
    }
    let mode = r.string("alphaMode").unwrap_or("opaque");
    surface.alpha = match mode {
        "opaque" => AlphaMode::Opaque,
        "blend" => AlphaMode::Blend,
        "mask" => AlphaMode::Mask(r.f32_in_range("alphaCutoff")?),
        other => {
            warn(format!(
                "alphaMode '{other}' is not one of {}: opaque",
                AlphaMode::NAMES.join(", ")
            ));
            AlphaMode::Opaque
        }
    };
    if surface.alpha == AlphaMode::Opaque && surface.opacity < 1.0 {
        warn(format!(
            "opacity {} under alphaMode opaque is drawn opaque (alphaMode blend composites it)",
            surface.opacity
        ));
    }
    Ok(Some(State::ready(MaterialModel {
        color_sampler,
        // An isosurface has no attributes: a named one is the default color.
        coloring: Coloring::Flat(flat),
        surface: Some(surface),
    })))
}
