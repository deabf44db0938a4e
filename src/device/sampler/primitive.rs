//! ANARI's `primitive` sampler (ANARI_KHR_SAMPLER_PRIMITIVE): a value per
//! primitive, read from an array at the primitive's number plus
//! `inOffset`.

use super::checked;
use crate::device::geometry::attributes::{vec4s, ATTRIBUTE_ELEMENTS};
use crate::device::object::State;
use crate::device::table::{p, DefaultValue, Read, SubtypeInfo, EXT_PRIMITIVE_SAMPLER};
use crate::device::types::DataType as T;
use crate::scene::{Sampler, SamplerKind};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::SAMPLER,
    subtype: "primitive",
    description: "a color per primitive, from an array",
    extensions: &[EXT_PRIMITIVE_SAMPLER],
    params: &[
        p(
            "array",
            &[T::ARRAY1D],
            true,
            DefaultValue::None,
            "the values (FLOAT32 to FLOAT32_VEC4, UFIXED8 to UFIXED8_VEC4); a primitive past its end reads (0, 0, 0, 1)",
        )
        .elements(ATTRIBUTE_ELEMENTS),
        p(
            "inOffset",
            &[T::UINT64, T::UINT32],
            false,
            DefaultValue::None,
            "the entry of primitive 0 (default 0)",
        ),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let values = r
        .array("array", |a| vec4s("array", a))?
        .ok_or_else(|| "parameter 'array' (ARRAY1D of values) is required".to_string())?;
    let offset = r.set("inOffset").and_then(|v| v.u64()).unwrap_or(0);
    let sampler = Sampler::new(SamplerKind::Primitive { values, offset });
    Ok(Some(State::ready(checked(sampler)?)))
}
