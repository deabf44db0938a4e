//! The `default` renderer: emission-absorption ray casting with caveray's
//! shading modes. Its table holds the defaults of `RenderSettings`; a test
//! keeps the two equal.

use super::info::{p, Default, SubtypeInfo, EXT_BACKGROUND, EXT_SHADING, F32, VEC3};
use super::object::{Derived, State};
use super::read::Read;
use super::types::DataType as T;
use crate::render::{RenderSettings, Shading};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::RENDERER,
    subtype: "default",
    description: "emission-absorption ray casting with optional shadows and ambient occlusion",
    extensions: &[EXT_SHADING, EXT_BACKGROUND],
    params: &[
        p(
            "background",
            &[T::FLOAT32_VEC4],
            false,
            Default::Floats(&[0.0, 0.0, 0.0, 1.0]),
            "colour behind the volume, straight alpha",
        ),
        p(
            "shading",
            &[T::STRING],
            false,
            Default::Text("none"),
            "none | shadows | ao | shadows+ao | directional:N (N <= 64); default none",
        )
        .names(&[
            "none",
            "shadows",
            "ao",
            "shadows+ao",
            "directional:1",
            "directional:4",
            "directional:16",
        ]),
        p(
            "lightDirection",
            VEC3,
            false,
            Default::Floats(&[0.3, 0.5, 0.8]),
            "direction towards the parallel light of shadows",
        ),
        p(
            "stepFactor",
            F32,
            false,
            Default::Floats(&[1.0]),
            "step length in units of half the smallest voxel extent",
        )
        .range(0.1, 10.0),
        p(
            "terminationThreshold",
            F32,
            false,
            Default::Floats(&[0.99]),
            "opacity at which a ray stops; above 1 disables early termination",
        )
        .range(0.5, 1.01),
        p(
            "depthThreshold",
            F32,
            false,
            Default::Floats(&[0.5]),
            "accumulated opacity at which channel.depth is taken (0: the first visible sample), so geometry behind a faint haze shows",
        )
        .range(0.0, 1.0),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    settings(r).map(|s| Some(State::Renderer(Derived::Ready(s))))
}

/// The settings the committed parameters describe.
pub fn settings(r: &Read<'_>) -> Result<RenderSettings, String> {
    let light = r.vec3("lightDirection")?;
    let s = RenderSettings {
        background: r.vec4("background")?,
        shading: r
            .string("shading")
            .unwrap_or_default()
            .parse::<Shading>()
            .map_err(|e| e.to_string())?,
        light: light
            .try_normalize()
            .ok_or_else(|| format!("lightDirection {light} has no direction"))?,
        step_factor: r.f32("stepFactor")?,
        termination: r.f32("terminationThreshold")?,
        depth_threshold: r.f32("depthThreshold")?,
    };
    s.validate().map_err(|e| e.to_string())?;
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::value::Params;

    #[test]
    fn the_table_holds_the_default_settings() {
        let unset = Params::default();
        assert_eq!(
            settings(&Read::new(&unset, INFO.params)),
            Ok(RenderSettings::default())
        );
    }
}
