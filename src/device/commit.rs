//! What `anariCommitParameters` derives for each implemented subtype. Every
//! function returns the derived value or a message naming what is wrong;
//! warnings about accepted-but-odd input go to `warn`.

use std::sync::Arc;

use glam::{UVec3, Vec3, Vec4};

use super::object::{ObjectRef, State, VolumeModel};
use super::types::DataType;
use super::value::{words, Params};
use super::{StructuredVolume, TransferFunction, Voxels};
use crate::render::{RenderSettings, Shading};

/// Voxel types a structured regular field accepts; UINT8/UINT16 are read
/// as their fixed-point twins with a warning.
const VOXEL_TYPES: &str = "UFIXED8, UFIXED16, FIXED16, FLOAT32 or FLOAT64";

pub fn structured_regular(
    p: &Params,
    warn: &mut dyn FnMut(String),
) -> Result<Arc<StructuredVolume>, String> {
    let data = p
        .object("data")
        .ok_or("parameter 'data' (ARRAY3D) is required")?;
    let array_guard = data.lock();
    let State::Array(array) = &array_guard.state else {
        return Err(format!("'data' is {}, not an array", data.describe()));
    };
    let [nx, ny, nz] = array.dims();
    let dims = UVec3::new(dim(nx)?, dim(ny)?, dim(nz)?);
    let bytes = array.bytes();
    let voxels = match array.element() {
        DataType::UFIXED8 => Voxels::U8(bytes.to_vec()),
        DataType::UINT8 => {
            warn("UINT8 voxels are read as UFIXED8 (0..255 maps to 0..1)".into());
            Voxels::U8(bytes.to_vec())
        }
        DataType::UFIXED16 | DataType::UINT16 => {
            if array.element() == DataType::UINT16 {
                warn("UINT16 voxels are read as UFIXED16 (0..65535 maps to 0..1)".into());
            }
            Voxels::U16(words(bytes).map(u16::from_ne_bytes).collect())
        }
        DataType::FIXED16 => Voxels::F32(
            words(bytes)
                .map(|w| (f32::from(i16::from_ne_bytes(w)) / 32767.0).max(-1.0))
                .collect(),
        ),
        DataType::FLOAT32 => Voxels::F32(array.f32s()),
        DataType::FLOAT64 => {
            Voxels::F32(words(bytes).map(|w| f64::from_ne_bytes(w) as f32).collect())
        }
        other => {
            return Err(format!(
                "'data' holds {other}; a structured regular field needs {VOXEL_TYPES}"
            ))
        }
    };
    if let Some(filter) = p.string("filter") {
        match filter {
            "linear" => {}
            "nearest" => warn("filter 'nearest' is not implemented; sampling is linear".into()),
            other => return Err(format!("filter '{other}' is not one of nearest, linear")),
        }
    }
    let origin = p.vec3("origin").unwrap_or(Vec3::ZERO);
    let spacing = p.vec3("spacing").unwrap_or(Vec3::ONE);
    StructuredVolume::new(dims, voxels, origin, spacing)
        .map(Arc::new)
        .map_err(|e| e.to_string())
}

fn dim(n: u64) -> Result<u32, String> {
    u32::try_from(n)
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| format!("'data' dimension {n} is not in 1..=4294967295"))
}

pub fn transfer_function_1d(p: &Params) -> Result<VolumeModel, String> {
    let field = p
        .object("value")
        .ok_or("parameter 'value' (SPATIAL_FIELD) is required")?
        .clone();
    let (lo, hi) = match p.get("valueRange").and_then(|v| v.f32s()).as_deref() {
        Some(&[lo, hi]) => (lo, hi),
        _ => (0.0, 1.0),
    };
    let colors = match p.get("color") {
        None => vec![Vec4::ONE],
        Some(v) => match v.object() {
            Some(array) => array_values(array, "color", |element, f| match element {
                DataType::FLOAT32_VEC3 => Some(
                    f.chunks_exact(3)
                        .map(|c| Vec3::from_slice(c).extend(1.0))
                        .collect(),
                ),
                DataType::FLOAT32_VEC4 => Some(f.chunks_exact(4).map(Vec4::from_slice).collect()),
                _ => None,
            })?,
            None => {
                let f = v.f32s().unwrap_or_default();
                vec![if f.len() == 3 {
                    Vec3::from_slice(&f).extend(1.0)
                } else {
                    Vec4::from_slice(&f)
                }]
            }
        },
    };
    let opacities = match p.get("opacity") {
        None => vec![1.0],
        Some(v) => match v.object() {
            Some(array) => array_values(array, "opacity", |element, f| {
                (element == DataType::FLOAT32).then(|| f.to_vec())
            })?,
            None => vec![p.f32("opacity", 1.0)],
        },
    };
    let unit_distance = p.f32("unitDistance", 1.0);
    let tf = TransferFunction::new(colors, opacities, (lo, hi), unit_distance)
        .map_err(|e| e.to_string())?;
    Ok(VolumeModel {
        field,
        transfer_function: Arc::new(tf),
    })
}

/// The elements of a 1D array parameter, converted by `convert` from its
/// FLOAT32 components; `None` from `convert` means the wrong element type.
fn array_values<T>(
    object: &ObjectRef,
    name: &str,
    convert: impl Fn(DataType, &[f32]) -> Option<Vec<T>>,
) -> Result<Vec<T>, String> {
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

pub fn world(p: &Params) -> Result<Vec<ObjectRef>, String> {
    let Some(array) = p.object("volume") else {
        return Ok(Vec::new());
    };
    let guard = array.lock();
    let State::Array(a) = &guard.state else {
        return Err(format!("'volume' is {}, not an array", array.describe()));
    };
    if a.element() != DataType::VOLUME {
        return Err(format!(
            "'volume' array holds {}; expected ANARI_VOLUME",
            a.element()
        ));
    }
    Ok(a.objects.iter().flatten().cloned().collect())
}

pub fn renderer(p: &Params) -> Result<RenderSettings, String> {
    let mut s = RenderSettings::default();
    if let Some(b) = p.vec4("background") {
        s.background = b;
    }
    if let Some(name) = p.string("shading") {
        s.shading = name.parse::<Shading>().map_err(|e| e.to_string())?;
    }
    if let Some(l) = p.vec3("lightDirection") {
        s.light = l
            .try_normalize()
            .ok_or_else(|| format!("lightDirection {l} has no direction"))?;
    }
    s.step_factor = p.f32("stepFactor", s.step_factor);
    s.termination = p.f32("terminationThreshold", s.termination);
    s.validate().map_err(|e| e.to_string())?;
    Ok(s)
}
