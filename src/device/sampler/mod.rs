//! Samplers: one module per subtype (the three image samplers share one),
//! each committing to the scene's [`Sampler`], which a matte material's
//! `color` may name.

pub mod image;
pub mod primitive;
pub mod transform;

use std::sync::Arc;

use crate::device::table::{p, DefaultValue, ParamInfo, Read, MAT4};
use crate::device::types::DataType as T;
use crate::scene::{Sampler, ATTRIBUTE_NAMES};

/// A sampler after commit.
pub type SamplerModel = Arc<Sampler>;

/// Attribute names a sampler may read: the geometry's attributes, or
/// `none` (ANARI's default value (0, 0, 0, 1) throughout).
pub const IN_ATTRIBUTES: [&str; 6] = [
    "color",
    "attribute0",
    "attribute1",
    "attribute2",
    "attribute3",
    "none",
];

pub const IN_ATTRIBUTE: ParamInfo = p(
    "inAttribute",
    &[T::STRING],
    false,
    DefaultValue::Text("attribute0"),
    "the geometry attribute sampled: color, attribute0 to attribute3, or none (positions and normals are not offered; naming one is warned about and reads as none)",
)
.names(&IN_ATTRIBUTES);

pub const fn transform(name: &'static str, description: &'static str) -> ParamInfo {
    p(
        name,
        MAT4,
        false,
        DefaultValue::Floats(&[
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ]),
        description,
    )
}

pub const fn offset(name: &'static str, description: &'static str) -> ParamInfo {
    p(
        name,
        &[T::FLOAT32_VEC4],
        false,
        DefaultValue::Floats(&[0.0, 0.0, 0.0, 0.0]),
        description,
    )
}

/// The attribute slot `inAttribute` names (`None`: none).
pub fn in_attribute(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Option<usize> {
    let name = r.string("inAttribute").unwrap_or("attribute0");
    if name == "none" {
        return None;
    }
    let slot = ATTRIBUTE_NAMES.iter().position(|n| *n == name);
    if slot.is_none() {
        warn(format!(
            "inAttribute '{name}': caveray samples {}; read as none, (0, 0, 0, 1)",
            IN_ATTRIBUTES.join(", ")
        ));
    }
    slot
}

/// `sampler` after its maps are checked.
pub fn checked(sampler: Sampler) -> Result<SamplerModel, String> {
    sampler.check().map_err(|e| e.to_string())?;
    Ok(Arc::new(sampler))
}
