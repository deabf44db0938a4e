//! The renderers: emission-absorption ray casting with caveray's shading
//! modes. `default` shades surfaces as the reference device does (an eye
//! light blended with their color), so that hosts and the conformance
//! tool tuned on it see what they expect; `directLight` lights them by the
//! world's directional, point and spot lights and the ambient light.
//! Both read one table, which holds the defaults of `RenderSettings`; a
//! test keeps the two equal.

use super::object::State;
use super::table::Read;
use super::table::{
    p, DefaultValue, ParamInfo, SubtypeInfo, EXT_AMBIENT, EXT_BACKGROUND, EXT_BACKGROUND_IMAGE,
    EXT_SHADING, F32, VEC3,
};
use super::types::DataType as T;
use glam::Vec4;

use std::sync::Arc;

use crate::render::{
    BackgroundImage, ClipPlanes, RenderSettings, Sampling, Shading, SurfaceShading,
    MAX_CLIP_PLANES, STEP_FACTOR_RANGE,
};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::RENDERER,
    subtype: "default",
    description: "emission-absorption ray casting with optional shadows and ambient occlusion; surfaces in an eye light, as the reference device shades them",
    extensions: &[EXT_SHADING, EXT_BACKGROUND, EXT_BACKGROUND_IMAGE, EXT_AMBIENT],
    params: PARAMS,
    commit: Some(commit),
};

pub static DIRECT_LIGHT: SubtypeInfo = SubtypeInfo {
    kind: T::RENDERER,
    subtype: "directLight",
    description: "as default, with surfaces lit by the world's directional, point and spot lights and the ambient light",
    extensions: &[EXT_SHADING, EXT_BACKGROUND, EXT_BACKGROUND_IMAGE, EXT_AMBIENT],
    params: PARAMS,
    commit: Some(commit_direct_light),
};

const PARAMS: &[ParamInfo] = &[
        p(
            "background",
            &[T::FLOAT32_VEC4, T::ARRAY2D, T::ARRAY1D],
            false,
            DefaultValue::Floats(&[0.0, 0.0, 0.0, 1.0]),
            "color behind the volume, straight alpha; or an ARRAY2D of FLOAT32_VEC4 stretched over the frame (1 x N: a vertical gradient, bottom first); an ARRAY1D of N FLOAT32_VEC4 is that 1 x N gradient",
        )
        .elements(&[T::FLOAT32_VEC4]),
        p(
            "shading",
            &[T::STRING],
            false,
            DefaultValue::Text("none"),
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
            "ambientColor",
            VEC3,
            false,
            DefaultValue::Floats(&[1.0, 1.0, 1.0]),
            "color of the ambient light on surfaces (linear RGB)",
        ),
        p(
            "ambientRadiance",
            F32,
            false,
            DefaultValue::Floats(&[1.0]),
            "strength of the ambient light on surfaces under directLight: 1 adds a tenth of a surface's color, a fill that keeps the lights' shading",
        )
        .at_least(0.0),
        p(
            "eyeLightBlendRatio",
            F32,
            false,
            DefaultValue::Floats(&[0.5]),
            "under default: the share of a surface's color that faces the eye, color x (ratio |n . v| + 1 - ratio)",
        )
        .range(0.0, 1.0),
        p(
            "lightDirection",
            VEC3,
            false,
            DefaultValue::Floats(&[0.3, 0.5, 0.8]),
            "direction towards the parallel light of shadows",
        ),
        p(
            "stepFactor",
            F32,
            false,
            DefaultValue::Floats(&[1.0]),
            "multiplies the step that volumeSamplingRate sets (at the default rate, the step in units of half the smallest voxel extent)",
        )
        .range(STEP_FACTOR_RANGE.0, STEP_FACTOR_RANGE.1),
        p(
            "volumeSamplingRate",
            F32,
            false,
            DefaultValue::Floats(&[2.0]),
            "samples per smallest voxel extent (2: half-voxel steps); stepFactor scales the step further",
        )
        .range(0.01, 16.0),
        p(
            "terminationThreshold",
            F32,
            false,
            DefaultValue::Floats(&[0.99]),
            "opacity at which a ray stops; above 1 disables early termination",
        )
        .range(0.5, 1.01),
        p(
            "depthThreshold",
            F32,
            false,
            DefaultValue::Floats(&[0.5]),
            "accumulated opacity at which channel.depth is taken (0: the first visible sample), so geometry behind a faint haze shows",
        )
        .range(0.0, 1.0),
        p(
            "clipPlane",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "up to 8 planes (n, d), ARRAY1D of FLOAT32_VEC4: rays keep the points p with dot(n, p) < d",
        )
        .elements(&[T::FLOAT32_VEC4]),
        p(
            "emptySpaceSkipping",
            &[T::BOOL],
            false,
            DefaultValue::Bool(true),
            "leap over bricks of the volume its transfer function leaves clear; the image does not change (false: march every step, for comparison)",
        ),
        p(
            "gpuSampling",
            &[T::STRING],
            false,
            DefaultValue::Text("exact"),
            "exact | filtered: on the GPU, the shader's trilinear interpolation (the reference's arithmetic), or one hardware-filtered fetch per sample and a table with the step's opacity correction baked in (faster; not with stereo re-projection)",
        )
        .names(&Sampling::NAMES),
        p(
            "levelOfDetail",
            F32,
            false,
            DefaultValue::Floats(&[0.0]),
            "0: full detail; F > 0, with gpuSampling filtered: the volume's mip level log2(F x pixel footprint / voxel) and a step 2^level longer where a pixel covers more than 1/F voxels (GPU only)",
        )
        .range(0.0, 16.0),
];

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    settings(r).map(|s| Some(State::ready(s)))
}

fn commit_direct_light(
    r: &Read<'_>,
    _warn: &mut dyn FnMut(String),
) -> Result<Option<State>, String> {
    let mut s = settings(r)?;
    s.surface_shading = SurfaceShading::Lights;
    Ok(Some(State::ready(s)))
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
        ambient: r.vec3("ambientColor")?
            * r.f32_in_range("ambientRadiance")?
            * crate::render::shapes::AMBIENT_SCALE,
        step_factor: r.f32_in_range("stepFactor")?,
        sampling_rate: r.f32_in_range("volumeSamplingRate")?,
        termination: r.f32("terminationThreshold")?,
        depth_threshold: r.f32("depthThreshold")?,
        clip_planes: clip_planes(r)?,
        background_image: background_image(r)?,
        skipping: r.bool("emptySpaceSkipping")?,
        level_of_detail: r.f32("levelOfDetail")?,
        surface_shading: SurfaceShading::EyeLight {
            blend: r.f32_in_range("eyeLightBlendRatio")?,
        },
        sampling: r
            .string("gpuSampling")
            .unwrap_or_default()
            .parse::<Sampling>()
            .map_err(|e| e.to_string())?,
        // Not a renderer parameter: a world's directional light sets it
        // when a frame renders.
        ..RenderSettings::default()
    };
    s.validate().map_err(|e| e.to_string())?;
    Ok(s)
}

/// `background` as an image, if it is an array.
fn background_image(r: &Read<'_>) -> Result<Option<Arc<BackgroundImage>>, String> {
    // pynari's samples give a gradient as a list of colours, bottom first.
    let column = r.object("background").is_some_and(|o| o.kind == T::ARRAY1D);
    r.array_of("background", T::FLOAT32_VEC4, |a| {
        let [w, h, _] = a.dims();
        let (w, h) = if column { (1, w) } else { (w, h) };
        let pixels: Vec<Vec4> = a.f32s().chunks_exact(4).map(Vec4::from_slice).collect();
        let size = glam::UVec2::new(
            u32::try_from(w).map_err(|_| format!("'background' is {w} wide"))?,
            u32::try_from(h).map_err(|_| format!("'background' is {h} high"))?,
        );
        BackgroundImage::new(size, pixels)
            .map(Arc::new)
            .ok_or_else(|| format!("'background' of {w}x{h} has no pixels"))
    })
}

/// The `clipPlane` array, if set.
fn clip_planes(r: &Read<'_>) -> Result<ClipPlanes, String> {
    let planes = r.array_of("clipPlane", T::FLOAT32_VEC4, |a| {
        let planes: Vec<Vec4> = a.f32s().chunks_exact(4).map(Vec4::from_slice).collect();
        ClipPlanes::new(&planes).ok_or_else(|| {
            format!(
                "'clipPlane' holds {} planes; caveray takes at most {MAX_CLIP_PLANES}",
                planes.len()
            )
        })
    })?;
    Ok(planes.unwrap_or_default())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::object::Params;

    #[test]
    fn the_table_holds_the_default_settings() {
        let unset = Params::default();
        assert_eq!(
            settings(&Read::new(&unset, INFO.params)),
            Ok(RenderSettings::default())
        );
    }
}
