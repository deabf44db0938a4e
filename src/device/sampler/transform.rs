//! ANARI's `transform` sampler (ANARI_KHR_SAMPLER_TRANSFORM): an attribute
//! through a 4 x 4 matrix and an offset, as the color.

use super::{checked, in_attribute, offset, transform, IN_ATTRIBUTE};
use crate::device::object::State;
use crate::device::table::{Read, SubtypeInfo, EXT_TRANSFORM_SAMPLER};
use crate::device::types::DataType as T;
use crate::scene::{Sampler, SamplerKind};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::SAMPLER,
    subtype: "transform",
    description: "an attribute through a matrix and an offset",
    extensions: &[EXT_TRANSFORM_SAMPLER],
    params: &[
        IN_ATTRIBUTE,
        transform("outTransform", "applied to the attribute (x, y, z, w)"),
        transform(
            "transform",
            "outTransform by the name the reference device and the conformance tool use; outTransform wins where both are set",
        ),
        offset("outOffset", "added after outTransform"),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let sampler = Sampler {
        in_attribute: in_attribute(r, warn),
        out_transform: if r.set("outTransform").is_none() && r.set("transform").is_some() {
            r.mat4("transform")?
        } else {
            r.mat4("outTransform")?
        },
        out_offset: r.vec4("outOffset")?,
        ..Sampler::new(SamplerKind::Transform)
    };
    Ok(Some(State::ready(checked(sampler)?)))
}
