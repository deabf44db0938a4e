//! ANARI's `physicallyBased` material (ANARI_KHR_MATERIAL_PHYSICALLY_BASED):
//! glTF's metallic-roughness model. The default renderer shows its base
//! color in the eye light as it shows a matte one (the reference device's
//! look) plus what it emits; `directLight` reflects the world's lights off
//! it by render/shapes/brdf.rs. The layers glTF adds beyond these
//! (clearcoat, sheen, transmission, ...) are accepted and not modelled.

use glam::Vec3;

use crate::device::object::State;
use crate::device::table::{p, DefaultValue, ParamInfo, Read, SubtypeInfo, EXT_PBR, F32, VEC3};
use crate::device::types::DataType as T;

use super::MaterialModel;
use crate::render::iso::Coloring;
use crate::scene::{Pbr, SurfaceMaterial};

/// A parameter read and not modelled: hosts set them, and hear nothing.
const fn unmodelled(name: &'static str, types: &'static [T]) -> ParamInfo {
    p(
        name,
        types,
        false,
        DefaultValue::None,
        "accepted; not modelled (caveray shades base color, metallic, roughness and emissive)",
    )
}

const NUMBER: &[T] = &[T::FLOAT32, T::SAMPLER, T::STRING];
const COLOR: &[T] = &[T::FLOAT32_VEC3, T::SAMPLER, T::STRING];

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::MATERIAL,
    subtype: "physicallyBased",
    description: "glTF's metallic-roughness material: base color, metallic, roughness, emissive",
    extensions: &[EXT_PBR],
    params: &[
        p(
            "baseColor",
            super::COLOR_TYPES,
            false,
            DefaultValue::Floats(&[1.0, 1.0, 1.0]),
            "linear RGB in [0, 1], the name of the geometry attribute that colors it (color, attribute0 to attribute3), or a sampler (its x, y, z)",
        ),
        super::OPACITY,
        super::ALPHA_MODE,
        super::ALPHA_CUTOFF,
        p(
            "metallic",
            NUMBER,
            false,
            DefaultValue::Floats(&[1.0]),
            "0 a dielectric (4 % white highlights), 1 a metal (highlights of its base color); a constant (a sampler or attribute name is read as the default, with a warning)",
        )
        .range(0.0, 1.0),
        p(
            "roughness",
            NUMBER,
            false,
            DefaultValue::Floats(&[1.0]),
            "0 mirror-like (sharpened to 0.03 at most), 1 fully rough; a constant, as metallic",
        )
        .range(0.0, 1.0),
        p(
            "emissive",
            VEC3,
            false,
            DefaultValue::Floats(&[0.0, 0.0, 0.0]),
            "linear RGB the surface gives off, added under either renderer",
        ),
        unmodelled("normal", &[T::SAMPLER]),
        unmodelled("occlusion", &[T::SAMPLER]),
        unmodelled("specular", NUMBER),
        unmodelled("specularColor", COLOR),
        unmodelled("clearcoat", NUMBER),
        unmodelled("clearcoatRoughness", NUMBER),
        unmodelled("clearcoatNormal", &[T::SAMPLER]),
        unmodelled("transmission", NUMBER),
        unmodelled("ior", NUMBER),
        unmodelled("thickness", NUMBER),
        unmodelled("attenuationDistance", F32),
        unmodelled("attenuationColor", VEC3),
        unmodelled("sheenColor", COLOR),
        unmodelled("sheenRoughness", NUMBER),
        unmodelled("iridescence", NUMBER),
        unmodelled("iridescenceIor", F32),
        unmodelled("iridescenceThickness", NUMBER),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let (color, color_sampler, flat) = super::color(r, "baseColor", Vec3::ONE, warn)?;
    let (opacity, opacity_sampler, alpha) = super::opacity_and_alpha(r, warn)?;
    let emissive = r.vec3("emissive")?;
    if !(emissive.is_finite() && emissive.min_element() >= 0.0) {
        return Err(format!(
            "emissive {emissive} must be finite and not negative"
        ));
    }
    let pbr = Pbr {
        metallic: {
            super::warn_unless_constant(r, "metallic", warn);
            r.f32_in_range("metallic")?
        },
        roughness: {
            super::warn_unless_constant(r, "roughness", warn);
            r.f32_in_range("roughness")?
        },
        emissive,
    };
    Ok(Some(State::ready(MaterialModel {
        color_sampler,
        opacity_sampler,
        coloring: Coloring::Flat(flat),
        surface: Some(SurfaceMaterial {
            color,
            opacity,
            alpha,
            pbr: Some(pbr),
        }),
    })))
}
