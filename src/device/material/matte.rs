//! ANARI's `matte` material (ANARI_KHR_MATERIAL_MATTE): one color.
//! Surfaces are opaque here; an opacity below 1 is drawn opaque, said so.

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_MATTE, F32};
use crate::device::types::DataType as T;
use crate::render::iso::Coloring;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::MATERIAL,
    subtype: "matte",
    description: "one color (linear RGB), lit by the renderer's shading",
    extensions: &[EXT_MATTE],
    params: &[
        p(
            "color",
            &[T::FLOAT32_VEC3, T::FLOAT32_VEC4, T::STRING],
            false,
            DefaultValue::Floats(&[0.8, 0.8, 0.8]),
            "the surface's color, linear RGB in [0, 1] (a fourth component is ignored); an attribute name is drawn in the default color, as an isosurface has no attributes",
        ),
        p(
            "opacity",
            F32,
            false,
            DefaultValue::Floats(&[1.0]),
            "surfaces are drawn opaque; below 1 is warned about",
        )
        .range(0.0, 1.0),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    if let Some(name) = r.set("color").and_then(|v| v.string()) {
        warn(format!(
            "color names the attribute '{name}'; isosurfaces have no attributes, so the surface is drawn in the default color"
        ));
    }
    let color = match r.set("color").and_then(|v| v.f32s()) {
        Some(f) if f.len() == 4 => glam::Vec3::from_slice(&f),
        _ => r.vec3("color")?,
    };
    if !color.is_finite() {
        return Err(format!("color {color} must be finite"));
    }
    let clamped = color.clamp(glam::Vec3::ZERO, glam::Vec3::ONE);
    if clamped != color {
        warn(format!("color {color} lies outside [0, 1]; clamped"));
    }
    let opacity = r.f32("opacity")?;
    if opacity < 1.0 {
        warn(format!("opacity {opacity}: caveray draws surfaces opaque"));
    }
    Ok(Some(State::ready(Coloring::Flat(clamped))))
}
