//! Materials: one module per subtype, each giving a surface its color
//! before the renderer's shading, and what `matte` and `physicallyBased`
//! read alike (a color, an opacity and how it shows).

pub mod curvature;
pub mod matte;
pub mod physically_based;

use glam::Vec3;

use super::object::ObjectRef;
use super::table::{p, DefaultValue, ParamInfo, Read, F32};
use super::types::DataType as T;
pub use crate::render::iso::Coloring;
use crate::scene::{
    AlphaMode, ColorSource, OpacitySource, Source, SurfaceMaterial, ATTRIBUTE_NAMES,
};

pub const OPACITY: ParamInfo = p(
    "opacity",
    &[T::FLOAT32, T::SAMPLER, T::STRING],
    false,
    DefaultValue::Floats(&[1.0]),
    "how much of what lies behind the surface it hides, under alphaMode blend or mask: a constant, the name of the geometry attribute that gives it (its first component), or a sampler (its x); times the color's fourth component where the color is an attribute or a sampler",
)
.range(0.0, 1.0);

/// Warns where number `name` is set as a sampler or an attribute name,
/// which caveray does not model: reading it then gives its default.
fn warn_unless_constant(r: &Read<'_>, name: &str, warn: &mut dyn FnMut(String)) {
    if r.object(name).is_some() || r.set(name).and_then(|v| v.string()).is_some() {
        warn(format!(
            "{name} from a sampler or an attribute is not modelled; the constant default is used"
        ));
    }
}

/// The types a material's color may be given as.
const COLOR_TYPES: &[T] = &[T::FLOAT32_VEC3, T::FLOAT32_VEC4, T::STRING, T::SAMPLER];

pub const ALPHA_MODE: ParamInfo = p(
    "alphaMode",
    &[T::STRING],
    false,
    DefaultValue::Text("opaque"),
    "opaque: opacity ignored; blend: composited with the volumes and surfaces behind in depth order (up to 8 translucent surfaces a ray); mask: opaque where opacity reaches alphaCutoff, else not drawn",
)
.names(&AlphaMode::NAMES);

pub const ALPHA_CUTOFF: ParamInfo = p(
    "alphaCutoff",
    F32,
    false,
    DefaultValue::Floats(&[0.5]),
    "the opacity from which a masked surface shows",
)
.range(0.0, 1.0);

/// Parameter `name` where the host names an attribute or gives a
/// sampler: its source (a sampler stands as the constant `fallback` until
/// a frame resolves it) and the sampler. None where it is a constant.
fn varying<C>(
    r: &Read<'_>,
    name: &str,
    fallback: C,
    warn: &mut dyn FnMut(String),
) -> Option<(Source<C>, Option<ObjectRef>)> {
    if let Some(sampler) = r.object(name).filter(|o| o.kind == T::SAMPLER) {
        return Some((Source::Constant(fallback), Some(sampler.clone())));
    }
    let attribute = r.set(name).and_then(|v| v.string())?;
    let source = match ATTRIBUTE_NAMES.iter().position(|n| *n == attribute) {
        Some(slot) => Source::Attribute(slot),
        None => {
            warn(format!(
                "{name} names '{attribute}'; caveray reads {}: the default is used",
                ATTRIBUTE_NAMES.join(", ")
            ));
            Source::Constant(fallback)
        }
    };
    Some((source, None))
}

/// Color parameter `name`: a constant, the name of an attribute, or a
/// sampler (resolved when a frame renders); with the flat color an
/// isosurface shows, which has no attributes.
fn color(
    r: &Read<'_>,
    name: &str,
    default: Vec3,
    warn: &mut dyn FnMut(String),
) -> Result<(ColorSource, Option<ObjectRef>, Vec3), String> {
    if let Some((source, sampler)) = varying(r, name, default, warn) {
        return Ok((source, sampler, default));
    }
    let color = match r.set(name).and_then(|v| v.f32s()) {
        Some(f) if f.len() == 4 => Vec3::from_slice(&f),
        _ => r.vec3(name)?,
    };
    if !color.is_finite() {
        return Err(format!("{name} {color} must be finite"));
    }
    let clamped = color.clamp(Vec3::ZERO, Vec3::ONE);
    if clamped != color {
        warn(format!("{name} {color} lies outside [0, 1]; clamped"));
    }
    Ok((ColorSource::Constant(clamped), None, clamped))
}

/// A material's `opacity` (a constant clamped into [0, 1], an attribute
/// or a sampler, resolved when a frame renders) and `alphaMode` (with
/// `alphaCutoff`).
fn opacity_and_alpha(
    r: &Read<'_>,
    warn: &mut dyn FnMut(String),
) -> Result<(OpacitySource, Option<ObjectRef>, AlphaMode), String> {
    let (opacity, sampler) = match varying(r, "opacity", 1.0, warn) {
        Some(varying) => varying,
        None => {
            let given = r.f32("opacity")?;
            if !given.is_finite() {
                return Err(format!("opacity {given} must be finite"));
            }
            let opacity = given.clamp(0.0, 1.0);
            if opacity != given {
                warn(format!("opacity {given} lies outside [0, 1]; clamped"));
            }
            (OpacitySource::Constant(opacity), None)
        }
    };
    let alpha = match r.string("alphaMode").unwrap_or("opaque") {
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
    if alpha == AlphaMode::Opaque {
        let given = match &opacity {
            _ if sampler.is_some() => Some("from a sampler".to_string()),
            OpacitySource::Constant(a) if *a < 1.0 => Some(a.to_string()),
            OpacitySource::Constant(_) => None,
            OpacitySource::Attribute(slot) => Some(format!("from {}", ATTRIBUTE_NAMES[*slot])),
            OpacitySource::Sampler(_) => Some("from a sampler".to_string()),
        };
        if let Some(given) = given {
            warn(format!(
                "opacity {given} under alphaMode opaque is drawn opaque (alphaMode blend composites it)"
            ));
        }
    }
    Ok((opacity, sampler, alpha))
}

/// A material after commit: how it colors an isosurface, and a surface of
/// primitives if it can (curvature needs a field's Hessian).
#[derive(Clone)]
pub struct MaterialModel {
    pub coloring: Coloring,
    pub surface: Option<SurfaceMaterial>,
    /// The samplers `color` and `opacity` name: resolved when a frame
    /// renders, so that their own later commits show.
    pub color_sampler: Option<ObjectRef>,
    pub opacity_sampler: Option<ObjectRef>,
}
