//! ANARI's `point` and `spot` lights (ANARI_KHR_LIGHT_POINT, _SPOT): light
//! from a position, `color` times `intensity` (radiant intensity) falling
//! off with the square of the distance; a spot's within half its
//! `openingAngle` of `direction`, fading over the `falloffAngle` inside
//! that edge. They light surfaces of primitives (up to 8 a world); the
//! volume shading keeps its one directional light.

use glam::Vec3;

use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, ParamInfo, SubtypeInfo, F32, VEC3};
use crate::device::types::DataType as T;
use crate::render::{Lamp, Spot};

const POSITION: ParamInfo = p(
    "position",
    VEC3,
    false,
    DefaultValue::Floats(&[0.0, 0.0, 0.0]),
    "where the light is",
);
const COLOR: ParamInfo = p(
    "color",
    VEC3,
    false,
    DefaultValue::Floats(&[1.0, 1.0, 1.0]),
    "light color",
);
const INTENSITY: ParamInfo = p(
    "intensity",
    F32,
    false,
    DefaultValue::Floats(&[1.0]),
    "radiant intensity: a surface d away facing the light receives color times intensity / d^2",
);

pub static POINT: SubtypeInfo = SubtypeInfo {
    kind: T::LIGHT,
    subtype: "point",
    description: "light from a point, falling off with the square of the distance (surfaces)",
    extensions: &["ANARI_KHR_LIGHT_POINT"],
    params: &[POSITION, COLOR, INTENSITY],
    commit: Some(commit_point),
};

pub static SPOT: SubtypeInfo = SubtypeInfo {
    kind: T::LIGHT,
    subtype: "spot",
    description: "a point light within a cone (surfaces)",
    extensions: &["ANARI_KHR_LIGHT_SPOT"],
    params: &[
        POSITION,
        p(
            "direction",
            VEC3,
            false,
            DefaultValue::Floats(&[0.0, 0.0, -1.0]),
            "the cone's axis, the way the light travels",
        ),
        p(
            "openingAngle",
            F32,
            false,
            DefaultValue::Floats(&[std::f32::consts::PI]),
            "the cone's full angle in radians",
        )
        .range(0.0, std::f32::consts::TAU),
        p(
            "falloffAngle",
            F32,
            false,
            DefaultValue::Floats(&[0.1]),
            "the angle in radians inside the cone's edge over which the light fades",
        )
        .range(0.0, std::f32::consts::PI),
        COLOR,
        INTENSITY,
    ],
    commit: Some(commit_spot),
};

fn lamp(r: &Read<'_>) -> Result<Lamp, String> {
    let position = r.vec3("position")?;
    let color = r.vec3("color")?;
    let intensity = r.f32("intensity")?;
    let usable = position.is_finite()
        && color.is_finite()
        && color.min_element() >= 0.0
        && intensity.is_finite()
        && intensity >= 0.0;
    if !usable {
        return Err(format!(
            "position {position}, color {color} and intensity {intensity} must be finite, color and intensity not negative"
        ));
    }
    Ok(Lamp {
        position,
        color: color * intensity,
        spot: None,
    })
}

fn commit_point(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    Ok(Some(State::ready(lamp(r)?)))
}

fn commit_spot(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let mut lamp = lamp(r)?;
    let direction = r.vec3("direction")?;
    let direction: Vec3 = direction
        .try_normalize()
        .ok_or_else(|| format!("direction {direction} has no direction"))?;
    let half = 0.5 * r.f32_in_range("openingAngle")?;
    let falloff = r.f32_in_range("falloffAngle")?;
    lamp.spot = Some(Spot {
        direction,
        cos_outer: half.cos(),
        cos_inner: (half - falloff).max(0.0).cos(),
    });
    Ok(Some(State::ready(lamp)))
}
