//! ANARI's `directional` light: parallel light from far away. The first
//! one in a world's `light` array gives the shading its light direction
//! and multiplies every lit sample by `color` times `irradiance` (a renderer
//! whose `shading` is `none` lights nothing).

use glam::Vec3;

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, F32, VEC3};
use crate::device::types::DataType as T;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::LIGHT,
    subtype: "directional",
    description: "parallel light: the shading's light direction and strength",
    extensions: &["ANARI_KHR_LIGHT_DIRECTIONAL"],
    params: &[
        p(
            "direction",
            VEC3,
            false,
            DefaultValue::Floats(&[0.0, 0.0, -1.0]),
            "direction the light travels in",
        ),
        p(
            "color",
            VEC3,
            false,
            DefaultValue::Floats(&[1.0, 1.0, 1.0]),
            "light color",
        ),
        p(
            "irradiance",
            F32,
            false,
            DefaultValue::Floats(&[1.0]),
            "strength: lit samples (shading other than none) are multiplied by color times irradiance",
        )
        .at_least(0.0),
    ],
    commit: Some(commit),
};

/// A directional light after commit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    /// Unit vector towards the light (the shading's convention).
    pub towards: Vec3,
    /// Color times irradiance.
    pub color: Vec3,
}

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let direction = r.vec3("direction")?;
    let towards = (-direction)
        .try_normalize()
        .ok_or_else(|| format!("direction {direction} has no direction"))?;
    let irradiance = r.f32("irradiance")?;
    let color = r.vec3("color")?;
    let usable = irradiance.is_finite()
        && irradiance >= 0.0
        && color.is_finite()
        && color.min_element() >= 0.0;
    if !usable {
        return Err(format!(
            "color {color} and irradiance {irradiance} must be finite and not negative"
        ));
    }
    Ok(Some(State::ready(DirectionalLight {
        towards,
        color: color * irradiance,
    })))
}
