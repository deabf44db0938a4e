//! The `transferFunction1D` volume: a spatial field classified by colour
//! and opacity maps spread over `valueRange`.

use std::sync::Arc;

use glam::{Vec3, Vec4};

use crate::device::info::{p, Default, SubtypeInfo, F32};
use crate::device::object::{Derived, ObjectRef, State};
use crate::device::read::Read;
use crate::device::types::DataType as T;
use crate::scene::TransferFunction;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::VOLUME,
    subtype: "transferFunction1D",
    description: "a spatial field classified by a 1D colour and opacity map",
    extensions: &["ANARI_KHR_VOLUME_TRANSFER_FUNCTION1D"],
    params: &[
        p(
            "value",
            &[T::SPATIAL_FIELD],
            true,
            Default::None,
            "the spatial field",
        ),
        p(
            "valueRange",
            &[T::FLOAT32_BOX1, T::FLOAT64_BOX1],
            false,
            Default::Floats(&[0.0, 1.0]),
            "field values mapped to the first and last entries",
        ),
        p(
            "color",
            &[T::ARRAY1D, T::FLOAT32_VEC3, T::FLOAT32_VEC4],
            false,
            Default::Floats(&[1.0, 1.0, 1.0]),
            "ARRAY1D of FLOAT32_VEC3/VEC4 spread over valueRange, or one colour",
        ),
        p(
            "opacity",
            &[T::ARRAY1D, T::FLOAT32],
            false,
            Default::Floats(&[1.0]),
            "ARRAY1D of FLOAT32 spread over valueRange, or one opacity",
        ),
        p(
            "unitDistance",
            F32,
            false,
            Default::Floats(&[1.0]),
            "world distance over which the opacities apply",
        ),
    ],
    commit: Some(commit),
};

/// A transfer-function volume after commit.
#[derive(Clone)]
pub struct VolumeModel {
    pub field: ObjectRef,
    pub transfer_function: Arc<TransferFunction>,
}

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let field = r
        .object("value")
        .ok_or("parameter 'value' (SPATIAL_FIELD) is required")?
        .clone();
    let [lo, hi] = r.floats::<2>("valueRange")?;
    let colors = match r.set("color").and_then(|v| v.object()) {
        Some(array) => array_values(array, "color", |element, f| match element {
            T::FLOAT32_VEC3 => Some(
                f.chunks_exact(3)
                    .map(|c| Vec3::from_slice(c).extend(1.0))
                    .collect(),
            ),
            T::FLOAT32_VEC4 => Some(f.chunks_exact(4).map(Vec4::from_slice).collect()),
            _ => None,
        })?,
        None => vec![match r.set("color").and_then(|v| v.f32s()) {
            Some(f) if f.len() == 4 => Vec4::from_slice(&f),
            _ => r.vec3("color")?.extend(1.0),
        }],
    };
    let opacities = match r.set("opacity").and_then(|v| v.object()) {
        Some(array) => array_values(array, "opacity", |element, f| {
            (element == T::FLOAT32).then(|| f.to_vec())
        })?,
        None => vec![r.f32("opacity")?],
    };
    let tf = TransferFunction::new(colors, opacities, (lo, hi), r.f32("unitDistance")?)
        .map_err(|e| e.to_string())?;
    Ok(Some(State::Volume(Derived::Ready(VolumeModel {
        field,
        transfer_function: Arc::new(tf),
    }))))
}

/// The elements of a 1D array parameter, converted by `convert` from its
/// FLOAT32 components; `None` from `convert` means the wrong element type.
fn array_values<V>(
    object: &ObjectRef,
    name: &str,
    convert: impl Fn(T, &[f32]) -> Option<Vec<V>>,
) -> Result<Vec<V>, String> {
    let guard = object.lock();
    let State::Array(array) = &guard.state else {
        return Err(format!("'{name}' is {}, not an array", object.describe()));
    };
    let values = convert(array.element(), &array.f32s()).ok_or_else(|| {
        let expected = if name == "opacity" {
            "FLOAT32"
        } else {
            "FLOAT32_VEC3 or FLOAT32_VEC4"
        };
        format!(
            "'{name}' array holds {}; expected {expected}",
            array.element()
        )
    })?;
    if values.is_empty() {
        return Err(format!("'{name}' array is empty"));
    }
    Ok(values)
}
