//! Spatial fields: one module per subtype, and the readers of value
//! arrays the subtypes share.

pub mod amr;
pub mod nanovdb;
pub mod structured_regular;
pub mod unstructured;

use crate::device::array::Array;
use crate::device::types::words;
use crate::device::types::DataType as T;

/// The element types a field's value arrays take.
const VALUE_TYPE_NAMES: &str = "UFIXED8, FIXED16, UFIXED16, FLOAT32 or FLOAT64";

/// Room for `n` elements, reserved fallibly: a field too large for this
/// machine fails its commit, not the host.
fn reserve<E>(n: u64, what: &str) -> Result<Vec<E>, String> {
    let oom = || {
        format!(
            "cannot allocate {} bytes for the field's {what}",
            n.saturating_mul(std::mem::size_of::<E>() as u64)
        )
    };
    let n = usize::try_from(n).map_err(|_| oom())?;
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| oom())?;
    Ok(v)
}

/// The first `n` elements of value array `a` (named `what` in errors) as
/// f32: fixed-point types mapped to [0, 1] or [-1, 1] as a structured
/// field maps them, floats as they are.
fn values(a: &Array, what: &str, n: u64) -> Result<Vec<f32>, String> {
    let mut out = reserve(n, "values")?;
    let n = n as usize;
    let bytes = a.bytes();
    match a.element() {
        T::UFIXED8 => out.extend(bytes.iter().take(n).map(|&b| f32::from(b) / 255.0)),
        T::UFIXED16 => out.extend(
            words::<2>(bytes)
                .take(n)
                .map(|w| f32::from(u16::from_ne_bytes(w)) / 65535.0),
        ),
        T::FIXED16 => out.extend(
            words::<2>(bytes)
                .take(n)
                .map(|w| (f32::from(i16::from_ne_bytes(w)) / 32767.0).max(-1.0)),
        ),
        T::FLOAT32 => out.extend(words::<4>(bytes).take(n).map(f32::from_ne_bytes)),
        T::FLOAT64 => out.extend(
            words::<8>(bytes)
                .take(n)
                .map(|w| f64::from_ne_bytes(w) as f32),
        ),
        other => return Err(format!("{what} holds {other}; it needs {VALUE_TYPE_NAMES}")),
    }
    Ok(out)
}
