//! ANARI's `image1D`, `image2D` and `image3D` samplers
//! (ANARI_KHR_SAMPLER_IMAGE1D, _IMAGE2D, _IMAGE3D): an attribute,
//! in-transformed, as coordinates into an image of colors, filtered
//! linearly or to the nearest texel, wrapped per axis, out-transformed.
//! VTK's color maps are `image1D` samplers of a scalar in attribute0.

use glam::UVec3;

use super::{checked, in_attribute, offset, transform, IN_ATTRIBUTE};
use crate::device::geometry::attributes::{vec4s, ATTRIBUTE_ELEMENTS};
use crate::device::object::State;
use crate::device::table::{p, DefaultValue, ParamInfo, Read, SubtypeInfo};
use crate::device::table::{EXT_IMAGE1D, EXT_IMAGE2D, EXT_IMAGE3D};
use crate::device::types::DataType as T;
use crate::scene::{Image, Sampler, SamplerKind, Wrap};

const FILTERS: [&str; 2] = ["linear", "nearest"];

/// The parameters of an image sampler whose `image` is an `array` of
/// `wraps` axes, each axis's wrap mode named by one of `wraps`.
macro_rules! image_params {
    ($array:expr, $($wrap:literal),+) => {
        [
            p(
                "image",
                &[$array],
                true,
                DefaultValue::None,
                "the colors (FLOAT32 to FLOAT32_VEC4, UFIXED8 to UFIXED8_VEC4, missing components as (x, 0, 0, 1)); texel i's centre at (i + 0.5) / n",
            )
            .elements(ATTRIBUTE_ELEMENTS),
            IN_ATTRIBUTE,
            p(
                "filter",
                &[T::STRING],
                false,
                DefaultValue::Text("linear"),
                "linear: blend the nearest texel centres; nearest: the nearest texel",
            )
            .names(&FILTERS),
            $(
                p(
                    $wrap,
                    &[T::STRING],
                    false,
                    DefaultValue::Text("clampToEdge"),
                    "coordinates outside [0, 1]: clampToEdge, repeat or mirrorRepeat",
                )
                .names(&Wrap::NAMES),
            )+
            transform("inTransform", "applied to the attribute (x, y, z, w) first"),
            offset("inOffset", "added after inTransform: the result's x (y, z) are the image coordinates"),
            transform("outTransform", "applied to the color read"),
            offset("outOffset", "added after outTransform"),
        ]
    };
}

static PARAMS_1D: [ParamInfo; 8] = image_params!(T::ARRAY1D, "wrapMode");
static PARAMS_2D: [ParamInfo; 9] = image_params!(T::ARRAY2D, "wrapMode1", "wrapMode2");
static PARAMS_3D: [ParamInfo; 10] =
    image_params!(T::ARRAY3D, "wrapMode1", "wrapMode2", "wrapMode3");

pub static INFO_1D: SubtypeInfo = SubtypeInfo {
    kind: T::SAMPLER,
    subtype: "image1D",
    description: "a row of colors read at an attribute: a color map",
    extensions: &[EXT_IMAGE1D],
    params: &PARAMS_1D,
    commit: Some(commit::<1>),
};

pub static INFO_2D: SubtypeInfo = SubtypeInfo {
    kind: T::SAMPLER,
    subtype: "image2D",
    description: "an image read at an attribute: a texture",
    extensions: &[EXT_IMAGE2D],
    params: &PARAMS_2D,
    commit: Some(commit::<2>),
};

pub static INFO_3D: SubtypeInfo = SubtypeInfo {
    kind: T::SAMPLER,
    subtype: "image3D",
    description: "a volume of colors read at an attribute",
    extensions: &[EXT_IMAGE3D],
    params: &PARAMS_3D,
    commit: Some(commit::<3>),
};

fn commit<const AXES: usize>(
    r: &Read<'_>,
    warn: &mut dyn FnMut(String),
) -> Result<Option<State>, String> {
    let read = r.array("image", |a| {
        let dims = a.dims();
        let texels = vec4s("image", a)?;
        Ok((dims, texels))
    })?;
    let (dims, texels) =
        read.ok_or_else(|| "parameter 'image' (an array of colors) is required".to_string())?;
    let dims = dims.map(|d| u32::try_from(d).unwrap_or(u32::MAX));
    let filter = r.string("filter").unwrap_or("linear");
    if !FILTERS.contains(&filter) {
        warn(format!(
            "filter '{filter}' is neither linear nor nearest: linear"
        ));
    }
    let names: &[&str] = match AXES {
        1 => &["wrapMode"],
        2 => &["wrapMode1", "wrapMode2"],
        _ => &["wrapMode1", "wrapMode2", "wrapMode3"],
    };
    let mut wrap = [Wrap::ClampToEdge; 3];
    for (k, name) in names.iter().enumerate() {
        let given = r.string(name).unwrap_or("clampToEdge");
        wrap[k] = Wrap::from_name(given).unwrap_or_else(|| {
            warn(format!(
                "{name} '{given}' is not one of {}: clampToEdge",
                Wrap::NAMES.join(", ")
            ));
            Wrap::ClampToEdge
        });
    }
    let image = Image::new(UVec3::from(dims), texels, filter != "nearest", wrap)
        .map_err(|e| format!("image: {e}"))?;
    let sampler = Sampler {
        in_attribute: in_attribute(r, warn),
        in_transform: r.mat4("inTransform")?,
        in_offset: r.vec4("inOffset")?,
        out_transform: r.mat4("outTransform")?,
        out_offset: r.vec4("outOffset")?,
        ..Sampler::new(SamplerKind::Image(image))
    };
    Ok(Some(State::ready(checked(sampler)?)))
}
