//! The `transferFunction1D` volume: a spatial field classified by color
//! and opacity maps spread over `valueRange`.

use std::sync::Arc;

use glam::Vec4;

use crate::device::array::Array;
use crate::device::elements::{clamp_unit, colors, scalars, COLOR_ELEMENTS, COLOR_TYPES};
use crate::device::object::{ObjectRef, State};
use crate::device::table::Read;
use crate::device::table::{id_param, p, DefaultValue, SubtypeInfo, F32};
use crate::device::types::DataType as T;
use crate::scene::TransferFunction;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::VOLUME,
    subtype: "transferFunction1D",
    description: "a spatial field classified by a 1D color and opacity map",
    extensions: &["ANARI_KHR_VOLUME_TRANSFER_FUNCTION1D"],
    params: &[
        // Required in practice: `value`, or the older `field`.
        p("value", &[T::SPATIAL_FIELD], false, DefaultValue::None, "the spatial field"),
        p("field", &[T::SPATIAL_FIELD], false, DefaultValue::None,
          "the spatial field, under its pre-1.0 name (value wins if both are set)"),
        p("valueRange", &[T::FLOAT32_BOX1, T::FLOAT64_BOX1, T::FLOAT32_VEC2], false,
          DefaultValue::Floats(&[0.0, 1.0]),
          "field values mapped to the first and last entries; lo == hi (a constant field) maps that value to the middle"),
        p("color", &[T::ARRAY1D, T::FLOAT32_VEC3, T::FLOAT32_VEC4], false,
          DefaultValue::Floats(&[1.0, 1.0, 1.0]),
          "ARRAY1D (FLOAT32, UFIXED8, UFIXED16 or UFIXED32 with 1 to 4 components, or UFIXED8_*_SRGB) spread over valueRange, or one color; out of [0, 1] clamped")
            .elements(COLOR_ELEMENTS),
        p("opacity", &[T::ARRAY1D, T::FLOAT32], false, DefaultValue::Floats(&[1.0]),
          "ARRAY1D of FLOAT32 spread over valueRange, or one opacity; out of [0, 1] clamped")
            .elements(&[T::FLOAT32, T::FLOAT64])
            .range(0.0, 1.0),
        p("unitDistance", F32, false, DefaultValue::Floats(&[1.0]),
          "world distance over which the opacities apply"),
        id_param("the volume's number in the frame's objectId channel (default: none, UINT32 max)"),
    ],
    commit: Some(commit),
};

/// A transfer-function volume after commit.
#[derive(Clone)]
pub struct VolumeModel {
    pub field: ObjectRef,
    pub transfer_function: Arc<TransferFunction>,
    pub id: u32,
}

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let field = r
        .object("value")
        .or_else(|| r.object("field"))
        .ok_or("parameter 'value' (SPATIAL_FIELD) is required")?
        .clone();
    let [lo, hi] = r.floats::<2>("valueRange")?;
    let (lo, hi) = if lo == hi {
        // A constant field (hosts send its one value as the range): the
        // value lands in the middle of the maps.
        let half = 1e-3 * lo.abs().max(1.0);
        (lo - half, hi + half)
    } else {
        (lo, hi)
    };
    let mut colors = match array_values(r, "color", colors, COLOR_TYPES)? {
        Some(array) => array,
        None => vec![match r.set("color").and_then(|v| v.f32s()) {
            Some(f) if f.len() == 4 => Vec4::from_slice(&f),
            _ => r.vec3("color")?.extend(1.0),
        }],
    };
    let mut opacities = match array_values(r, "opacity", scalars, "FLOAT32 or FLOAT64")? {
        Some(array) => array,
        None => vec![r.f32("opacity")?],
    };
    let mut components: Vec<f32> = colors.iter().flat_map(|c| c.to_array()).collect();
    if let Some((n, i, x)) = clamp_unit(&mut components) {
        warn(format!(
            "{n} color components lie outside [0, 1] (the first: color[{}] component {} = {x}); clamped",
            i / 4,
            i % 4
        ));
        colors = components.chunks_exact(4).map(Vec4::from_slice).collect();
    }
    if let Some((n, i, x)) = clamp_unit(&mut opacities) {
        warn(format!(
            "{n} opacities lie outside [0, 1] (the first: opacity[{i}] = {x}); clamped"
        ));
    }
    let tf = TransferFunction::new(colors, opacities, (lo, hi), r.f32("unitDistance")?)
        .map_err(|e| e.to_string())?;
    Ok(Some(State::ready(VolumeModel {
        field,
        transfer_function: Arc::new(tf),
        id: r.id(),
    })))
}

/// The elements of array parameter `name`, read by `read`; `None` from it
/// means an element type that does not fit (`expected` says which do).
fn array_values<V>(
    r: &Read<'_>,
    name: &str,
    read: fn(&Array) -> Option<Vec<V>>,
    expected: &str,
) -> Result<Option<Vec<V>>, String> {
    r.array(name, |array| {
        let values = read(array).ok_or_else(|| {
            format!(
                "'{name}' array holds {}; expected {expected}",
                array.element()
            )
        })?;
        if values.is_empty() {
            return Err(format!("'{name}' array is empty"));
        }
        Ok(values)
    })
}
