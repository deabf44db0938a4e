//! The `structuredRegular` field: a vertex-centred grid, x fastest, over
//! [origin, origin + (dims - 1) * spacing].

use std::sync::Arc;

use glam::UVec3;

use crate::device::array::Array;
use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, VEC3};
use crate::device::types::words;
use crate::device::types::DataType as T;
use crate::scene::{Buf, Filter, SpatialField, StructuredVolume, VolumeError, Voxels, MAX_VOXELS};

/// Voxel types a structured regular field accepts; UINT8/UINT16 are read
/// as their fixed-point twins with a warning.
const VOXEL_TYPES: &str = "UFIXED8, UFIXED16, FIXED16, FLOAT32 or FLOAT64";

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::SPATIAL_FIELD,
    subtype: "structuredRegular",
    description:
        "vertex-centred regular grid, x fastest, sampled trilinearly or at the nearest vertex",
    extensions: &["ANARI_KHR_SPATIAL_FIELD_STRUCTURED_REGULAR"],
    params: &[
        p(
            "data",
            &[T::ARRAY3D],
            true,
            DefaultValue::None,
            "voxels: UFIXED8, UFIXED16, FIXED16, FLOAT32 or FLOAT64 (UINT8/UINT16 read as UFIXED)",
        )
        .elements(&[
            T::UFIXED8,
            T::UFIXED16,
            T::FIXED16,
            T::FLOAT32,
            T::FLOAT64,
            T::UINT8,
            T::UINT16,
        ]),
        p(
            "origin",
            VEC3,
            false,
            DefaultValue::Floats(&[0.0, 0.0, 0.0]),
            "position of voxel (0, 0, 0)",
        ),
        p(
            "spacing",
            VEC3,
            false,
            DefaultValue::Floats(&[1.0, 1.0, 1.0]),
            "distance between voxel centres",
        ),
        p(
            "filter",
            &[T::STRING],
            false,
            DefaultValue::Text("linear"),
            "linear (trilinear) or nearest (the nearest vertex); other names read as linear",
        )
        .names(&["linear", "nearest"]),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let (dims, voxels) = r
        .array("data", |array| read_voxels(array, r, warn))?
        .ok_or("parameter 'data' (ARRAY3D) is required")?;
    // Unknown enumeration values fall back to the default (the spec's rule).
    let filter = match r.string("filter") {
        Some("nearest") => Filter::Nearest,
        Some("linear") | None => Filter::Linear,
        Some(other) => {
            warn(format!(
                "filter '{other}' is not one of linear, nearest; sampling is linear"
            ));
            Filter::Linear
        }
    };
    // Voxels read in place keep their array alive as long as they are
    // this field's (a release while they are copies them).
    let holds = match voxels.in_place() {
        true => r.object("data").cloned().into_iter().collect(),
        false => Vec::new(),
    };
    let volume = StructuredVolume::new(dims, voxels, r.vec3("origin")?, r.vec3("spacing")?)
        .map_err(|e| e.to_string())?
        .with_filter(filter);
    Ok(Some(State::ready_holding(
        Arc::new(SpatialField::from(volume)),
        holds,
    )))
}

/// The grid's dimensions and voxels: the host's memory read in place
/// where it is a shared array of a type the renderers sample as stored,
/// else converted from the array's type (a copy, noted as a cost).
fn read_voxels(
    array: &Array,
    r: &Read<'_>,
    warn: &mut dyn FnMut(String),
) -> Result<(UVec3, Voxels), String> {
    let [nx, ny, nz] = array.dims();
    let dims = UVec3::new(dim(nx)?, dim(ny)?, dim(nz)?);
    let count = nx.saturating_mul(ny).saturating_mul(nz);
    if count > MAX_VOXELS {
        return Err(VolumeError::TooManyVoxels { dims }.to_string());
    }
    let n = count as usize;
    if let Some(lent) = array.lent() {
        let lent = || Arc::clone(lent);
        let in_place = match array.element() {
            T::UFIXED8 | T::UINT8 => Buf::lent(lent(), n).map(Voxels::U8),
            T::UFIXED16 | T::UINT16 => Buf::lent(lent(), n).map(Voxels::U16),
            T::FIXED16 => Buf::lent(lent(), n).map(Voxels::I16),
            T::FLOAT32 => Buf::lent(lent(), n).map(Voxels::F32),
            _ => None,
        };
        if let Some(voxels) = in_place {
            match array.element() {
                T::UINT8 => warn("UINT8 voxels are read as UFIXED8 (0..255 maps to 0..1)".into()),
                T::UINT16 => {
                    warn("UINT16 voxels are read as UFIXED16 (0..65535 maps to 0..1)".into())
                }
                _ => {}
            }
            return Ok((dims, voxels));
        }
        r.cost(format!(
            "'data' ({}, {} bytes) is copied: the renderers sample {VOXEL_TYPES} from the host's memory in place, aligned to their size",
            array.element(),
            array.bytes().len()
        ));
    }
    let bytes = array.bytes();
    let voxels = match array.element() {
        T::UFIXED8 => Voxels::U8(gather(n, bytes.iter().copied())?.into()),
        T::UINT8 => {
            warn("UINT8 voxels are read as UFIXED8 (0..255 maps to 0..1)".into());
            Voxels::U8(gather(n, bytes.iter().copied())?.into())
        }
        T::UFIXED16 | T::UINT16 => {
            if array.element() == T::UINT16 {
                warn("UINT16 voxels are read as UFIXED16 (0..65535 maps to 0..1)".into());
            }
            Voxels::U16(gather(n, words(bytes).map(u16::from_ne_bytes))?.into())
        }
        T::FIXED16 => Voxels::I16(gather(n, words(bytes).map(i16::from_ne_bytes))?.into()),
        T::FLOAT32 => Voxels::F32(gather(n, words(bytes).map(f32::from_ne_bytes))?.into()),
        T::FLOAT64 => {
            Voxels::F32(gather(n, words(bytes).map(|w| f64::from_ne_bytes(w) as f32))?.into())
        }
        other => {
            return Err(format!(
                "'data' holds {other}; a structured regular field needs {VOXEL_TYPES}"
            ))
        }
    };
    Ok((dims, voxels))
}

/// The items collected into memory reserved up front, fallibly: a field
/// too large for this machine fails its commit, not the host.
fn gather<T>(n: usize, items: impl Iterator<Item = T>) -> Result<Vec<T>, String> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        format!(
            "cannot allocate {} bytes for the field's voxels",
            n.saturating_mul(std::mem::size_of::<T>())
        )
    })?;
    v.extend(items.take(n));
    Ok(v)
}

fn dim(n: u64) -> Result<u32, String> {
    u32::try_from(n)
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| format!("'data' dimension {n} is not in 1..=4294967295"))
}
