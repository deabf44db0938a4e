//! How linear color values become stored pixels and back: 8-bit
//! rounding as the shaders round, and the sRGB transfer curve.

/// WGSL's `pack4x8unorm` rounding (ties to even), so both renderers agree
/// to the bit on 8-bit output.
pub fn to_unorm8(x: f32) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0).round_ties_even() as u8
}

pub fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// `to_unorm8(linear_to_srgb(x))`, the same byte for every `x`, without
/// a power per channel: encoding a frame is a tenth of a fast frame's
/// time otherwise. The curve rises, so the byte is the number of
/// thresholds at or below `x`; one coarse table bucket (a float's exponent
/// and top seven mantissa bits, where the encoded value moves by less
/// than one step) holds the byte at its start and the one threshold it
/// may cross.
pub fn srgb8(x: f32) -> u8 {
    let table = srgb8_table();
    if x.is_nan() || x <= 0.0 {
        return 0;
    }
    if x >= 1.0 {
        return 255;
    }
    let (byte, threshold) = table[(x.to_bits() >> SRGB8_SHIFT) as usize];
    byte + u8::from(x >= threshold)
}

/// Float bits dropped to index [`srgb8`]'s table.
const SRGB8_SHIFT: u32 = 16;

fn srgb8_table() -> &'static [(u8, f32)] {
    static TABLE: std::sync::OnceLock<Vec<(u8, f32)>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let slow = |x: f32| to_unorm8(linear_to_srgb(x));
        // The smallest positive float at which the byte reaches k.
        let thresholds: Vec<f32> = (1..=255u8)
            .map(|k| {
                let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
                while hi - lo > 1 {
                    let mid = lo + (hi - lo) / 2;
                    if slow(f32::from_bits(mid)) >= k {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                f32::from_bits(hi)
            })
            .collect();
        let buckets = (1.0f32.to_bits() >> SRGB8_SHIFT) as usize;
        (0..buckets)
            .map(|b| {
                let start = f32::from_bits((b as u32) << SRGB8_SHIFT);
                let end = f32::from_bits(((b as u32 + 1) << SRGB8_SHIFT) - 1);
                let byte = thresholds.partition_point(|&t| t <= start) as u8;
                // The bucket's one threshold past its start, if any.
                let next = thresholds
                    .get(byte as usize)
                    .copied()
                    .filter(|&t| t <= end)
                    .unwrap_or(f32::INFINITY);
                (byte, next)
            })
            .collect()
    })
}

pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every byte's threshold and its neighbours, and a wide spread of
    /// floats besides, encode as the power curve does.
    #[test]
    fn the_table_encodes_every_float_as_the_curve_does() {
        let slow = |x: f32| to_unorm8(linear_to_srgb(x));
        let mut bits = 0u32;
        let end = 1.001f32.to_bits();
        while bits < end {
            for b in [bits, bits + 1, bits.saturating_sub(1)] {
                let x = f32::from_bits(b);
                assert_eq!(srgb8(x), slow(x), "{x:e}");
            }
            bits += 997;
        }
        for x in [
            f32::NAN,
            -1.0,
            -0.0,
            0.0,
            1.0,
            2.0,
            f32::INFINITY,
            f32::MIN_POSITIVE,
        ] {
            assert_eq!(srgb8(x), slow(x), "{x:e}");
        }
        // Each step's first float.
        let mut last = 0;
        let mut x = 0.0f32;
        while x < 1.0 {
            let got = srgb8(x);
            assert!(got >= last, "falls at {x:e}");
            last = got;
            x = f32::from_bits(x.to_bits() + 4093);
        }
        assert!(srgb8_table()
            .iter()
            .all(|&(byte, t)| byte < 255 || t.is_infinite()));
    }

    /// Within any one bucket the curve rises by less than one step: the
    /// table's premise.
    #[test]
    fn no_bucket_crosses_two_thresholds() {
        let slow = |x: f32| to_unorm8(linear_to_srgb(x));
        for b in 0..(1.0f32.to_bits() >> SRGB8_SHIFT) {
            let start = f32::from_bits(b << SRGB8_SHIFT);
            let end = f32::from_bits(((b + 1) << SRGB8_SHIFT) - 1);
            assert!(
                slow(end) - slow(start) <= 1,
                "bucket {b}: {start:e}..{end:e}"
            );
        }
    }
}
