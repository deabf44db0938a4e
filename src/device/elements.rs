//! Array elements as colors and opacities: every element type ANARI lets
//! a transfer function's `color` array or a geometry's attribute hold
//! (fixed-point, sRGB and float, one to four components), read into
//! linear RGBA. Missing color
//! components read as 0 and a missing alpha as 1, as the reference device
//! reads attributes.

use glam::Vec4;

use crate::device::array::Array;
use crate::device::types::words;
use crate::device::types::DataType as T;
use crate::render::encoding::srgb_to_linear;

/// How one element type is stored: components, their encoding.
#[derive(Clone, Copy)]
enum Encoding {
    Float32,
    Unorm8,
    Unorm16,
    Unorm32,
    /// 8-bit sRGB-encoded color, linear alpha (the `*_SRGB` types).
    Srgb8,
}

fn layout(t: T) -> Option<(Encoding, usize)> {
    use Encoding::*;
    Some(match t {
        T::FLOAT32 => (Float32, 1),
        T::FLOAT32_VEC2 => (Float32, 2),
        T::FLOAT32_VEC3 => (Float32, 3),
        T::FLOAT32_VEC4 => (Float32, 4),
        T::UFIXED8 => (Unorm8, 1),
        T::UFIXED8_VEC2 => (Unorm8, 2),
        T::UFIXED8_VEC3 => (Unorm8, 3),
        T::UFIXED8_VEC4 => (Unorm8, 4),
        T::UFIXED16 => (Unorm16, 1),
        T::UFIXED16_VEC2 => (Unorm16, 2),
        T::UFIXED16_VEC3 => (Unorm16, 3),
        T::UFIXED16_VEC4 => (Unorm16, 4),
        T::UFIXED32 => (Unorm32, 1),
        T::UFIXED32_VEC2 => (Unorm32, 2),
        T::UFIXED32_VEC3 => (Unorm32, 3),
        T::UFIXED32_VEC4 => (Unorm32, 4),
        T::UFIXED8_R_SRGB => (Srgb8, 1),
        T::UFIXED8_RA_SRGB => (Srgb8, 2),
        T::UFIXED8_RGB_SRGB => (Srgb8, 3),
        T::UFIXED8_RGBA_SRGB => (Srgb8, 4),
        _ => return None,
    })
}

/// The element types a color array may hold (what `layout` reads).
pub const COLOR_ELEMENTS: &[T] = &[
    T::FLOAT32,
    T::FLOAT32_VEC2,
    T::FLOAT32_VEC3,
    T::FLOAT32_VEC4,
    T::UFIXED8,
    T::UFIXED8_VEC2,
    T::UFIXED8_VEC3,
    T::UFIXED8_VEC4,
    T::UFIXED16,
    T::UFIXED16_VEC2,
    T::UFIXED16_VEC3,
    T::UFIXED16_VEC4,
    T::UFIXED32,
    T::UFIXED32_VEC2,
    T::UFIXED32_VEC3,
    T::UFIXED32_VEC4,
    T::UFIXED8_R_SRGB,
    T::UFIXED8_RA_SRGB,
    T::UFIXED8_RGB_SRGB,
    T::UFIXED8_RGBA_SRGB,
];

/// The color element types, for messages.
pub const COLOR_TYPES: &str =
    "FLOAT32, UFIXED8, UFIXED16 or UFIXED32 (1 to 4 components), or UFIXED8_R/RA/RGB/RGBA_SRGB";

/// The elements of a color array as linear RGBA, `None` for an element
/// type that is no color.
pub fn colors(array: &Array) -> Option<Vec<Vec4>> {
    let (encoding, n) = layout(array.element())?;
    let bytes = array.bytes();
    let components: Vec<f32> = match encoding {
        Encoding::Float32 => words(bytes).map(f32::from_ne_bytes).collect(),
        Encoding::Unorm8 | Encoding::Srgb8 => bytes.iter().map(|&b| f32::from(b) / 255.0).collect(),
        Encoding::Unorm16 => words(bytes)
            .map(|w| f32::from(u16::from_ne_bytes(w)) / 65535.0)
            .collect(),
        Encoding::Unorm32 => words(bytes)
            .map(|w| (f64::from(u32::from_ne_bytes(w)) / f64::from(u32::MAX)) as f32)
            .collect(),
    };
    // sRGB types: ...RA is (color, alpha); the other alphas are the 4th.
    let alpha_at = if array.element() == T::UFIXED8_RA_SRGB {
        1
    } else {
        3
    };
    Some(
        components
            .chunks_exact(n)
            .map(|c| {
                let mut rgba = [0.0, 0.0, 0.0, 1.0];
                for (i, &x) in c.iter().enumerate() {
                    let slot = if i == alpha_at { 3 } else { i };
                    rgba[slot] = match encoding {
                        Encoding::Srgb8 if slot < 3 => srgb_to_linear(x),
                        _ => x,
                    };
                }
                Vec4::from(rgba)
            })
            .collect(),
    )
}

/// The elements of a scalar FLOAT32 or FLOAT64 array, `None` for others.
pub fn scalars(array: &Array) -> Option<Vec<f32>> {
    let bytes = array.bytes();
    match array.element() {
        T::FLOAT32 => Some(words(bytes).map(f32::from_ne_bytes).collect()),
        T::FLOAT64 => Some(words(bytes).map(|w| f64::from_ne_bytes(w) as f32).collect()),
        _ => None,
    }
}

/// Clamps `values` into [0, 1] in place; the count of values changed and
/// the first of them, for the warning.
pub fn clamp_unit(values: &mut [f32]) -> Option<(usize, usize, f32)> {
    let mut first = None;
    let mut count = 0;
    for (i, x) in values.iter_mut().enumerate() {
        if x.is_finite() && !(0.0..=1.0).contains(x) {
            first.get_or_insert((i, *x));
            count += 1;
            *x = x.clamp(0.0, 1.0);
        }
    }
    first.map(|(i, x)| (count, i, x))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_listed_color_types_are_exactly_those_read() {
        for t in T::ALL {
            assert_eq!(
                layout(*t).is_some(),
                COLOR_ELEMENTS.contains(t),
                "{t} is read as a color but not listed, or listed but not read"
            );
        }
    }

    #[test]
    fn srgb_decodes_to_linear() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // 188/255 is about half the light.
        assert!((srgb_to_linear(188.0 / 255.0) - 0.5029).abs() < 1e-3);
    }
}
