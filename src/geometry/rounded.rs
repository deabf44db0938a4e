//! Numbers as messages show them: computed distances carry float tails
//! (`0.10000000000000009`) that say nothing to a reader and hide the
//! magnitude. Here because every room that reports a number may import
//! geometry.

use std::fmt;

/// Significant digits kept: enough to tell apart any two numbers a rig
/// or a camera is likely to hold, few enough to read at a glance.
const DIGITS: usize = 6;

/// Displays a number to [`DIGITS`] significant digits without trailing
/// zeros: `0.1`, `1500`, `2.5e-7`, `1e30`; non-finite values as `NaN`,
/// `inf`, `-inf`. Plain decimals from 1e-4 up to a million, an exponent
/// (as Rust writes one, `1e30`, `2.5e-7`) beyond.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rounded(pub f64);

impl From<f32> for Rounded {
    fn from(x: f32) -> Self {
        Rounded(f64::from(x))
    }
}

impl fmt::Display for Rounded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if !x.is_finite() {
            return write!(f, "{x}");
        }
        if x == 0.0 {
            // -0 reads as a sign error where none is meant.
            return f.write_str("0");
        }
        // The exponent after rounding (9.999996 rounds to 1.00000e1).
        let sci = format!("{:.*e}", DIGITS - 1, x);
        let (mantissa, exponent) = sci.split_once('e').unwrap_or((&sci, "0"));
        let exponent: i32 = exponent.parse().unwrap_or(0);
        if (-4..DIGITS as i32).contains(&exponent) {
            let decimals = (DIGITS as i32 - 1 - exponent).max(0) as usize;
            f.write_str(trim_zeros(&format!("{x:.decimals$}")))
        } else {
            write!(f, "{}e{exponent}", trim_zeros(mantissa))
        }
    }
}

/// `1.500` as `1.5`, `2.000` as `2`; text without a point is left alone.
fn trim_zeros(number: &str) -> &str {
    if number.contains('.') {
        number.trim_end_matches('0').trim_end_matches('.')
    } else {
        number
    }
}

#[cfg(test)]
mod tests {
    use super::Rounded;

    fn shown(x: f64) -> String {
        Rounded(x).to_string()
    }

    #[test]
    fn tails_go_and_magnitudes_stay() {
        assert_eq!(shown(0.10000000000000009), "0.1");
        assert_eq!(shown(0.1 + 0.2), "0.3");
        assert_eq!(shown(1500.0), "1500");
        assert_eq!(shown(2.5e-7), "2.5e-7");
        assert_eq!(shown(1e30), "1e30");
        assert_eq!(shown(1e-38), "1e-38");
        assert_eq!(shown(-0.063), "-0.063");
        assert_eq!(shown(89.99999999999997), "90");
        assert_eq!(shown(123456.7), "123457");
        assert_eq!(shown(1234567.0), "1.23457e6");
        assert_eq!(shown(9.9999996), "10");
        assert_eq!(shown(0.0001), "0.0001");
        assert_eq!(shown(0.00001), "1e-5");
        assert_eq!(shown(0.0000123456789), "1.23457e-5");
        assert_eq!(shown(0.015625), "0.015625");
        assert_eq!(shown(10000.0), "10000");
        assert_eq!(shown(-0.0), "0");
        assert_eq!(shown(f64::NAN), "NaN");
        assert_eq!(shown(f64::NEG_INFINITY), "-inf");
        assert_eq!(Rounded::from(0.1f32).to_string(), "0.1");
    }
}
