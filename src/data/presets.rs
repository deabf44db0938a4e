use glam::Vec4;

use super::DataError;
use crate::scene::{TransferFunction, TransferFunctionError, TABLE_SIZE};

/// Built-in transfer functions over the normalised value range [0, 1]
/// (callers usually stretch them over the data's range).
pub const PRESETS: [&str; 7] = [
    "phantom",
    "ct-skin-bone",
    "ct-bone",
    "mri",
    "grey",
    "shells",
    "level-set",
];

/// Control points (value, r, g, b, opacity), linearly interpolated.
type Points = &'static [(f32, f32, f32, f32, f32)];

// Tuned to the phantom's levels: brain 0.2 translucent, the small 0.3
// features opaque and warm, the 1.0 skull a thin translucent shell.
const PHANTOM: Points = &[
    (0.0, 0.0, 0.0, 0.0, 0.0),
    (0.12, 0.6, 0.3, 0.3, 0.0),
    (0.2, 0.85, 0.55, 0.5, 0.12),
    (0.26, 0.9, 0.6, 0.45, 0.15),
    (0.3, 1.0, 0.8, 0.2, 0.9),
    (0.4, 1.0, 0.8, 0.2, 0.9),
    (0.6, 0.7, 0.8, 0.95, 0.25),
    (1.0, 0.8, 0.85, 1.0, 0.5),
];
// Soft tissue as translucent skin, bone opaque and bright.
const CT_SKIN_BONE: Points = &[
    (0.0, 0.0, 0.0, 0.0, 0.0),
    (0.2, 0.55, 0.25, 0.15, 0.0),
    (0.3, 0.9, 0.6, 0.45, 0.06),
    (0.4, 0.95, 0.75, 0.6, 0.02),
    (0.55, 0.95, 0.9, 0.8, 0.5),
    (1.0, 1.0, 1.0, 0.95, 0.95),
];
const CT_BONE: Points = &[
    (0.0, 0.0, 0.0, 0.0, 0.0),
    (0.45, 0.8, 0.7, 0.5, 0.0),
    (0.6, 0.95, 0.9, 0.8, 0.6),
    (1.0, 1.0, 1.0, 1.0, 1.0),
];
const MRI: Points = &[
    (0.0, 0.0, 0.0, 0.0, 0.0),
    (0.1, 0.3, 0.1, 0.1, 0.0),
    (0.3, 0.85, 0.5, 0.4, 0.08),
    (0.6, 1.0, 0.85, 0.7, 0.35),
    (1.0, 1.0, 1.0, 1.0, 0.8),
];
// Translucent at the scale of a shell's thickness, so that rays cross all
// four shells: blue inner, amber outer, air (below 0.1) clear.
const SHELLS: Points = &[
    (0.0, 0.2, 0.4, 1.0, 0.0),
    (0.1, 0.2, 0.4, 1.0, 0.0),
    (0.5, 0.5, 0.8, 0.6, 0.15),
    (1.0, 1.0, 0.7, 0.2, 0.5),
];
const GREY: Points = &[(0.0, 0.0, 0.0, 0.0, 0.0), (1.0, 1.0, 1.0, 1.0, 1.0)];
// A signed distance over a range symmetric about 0 (a level set's narrow
// band): deep inside (the interior's tiles) and outside clear, the band
// inside a translucent blue, the surface (0.5) bright and opaque.
const LEVEL_SET: Points = &[
    (0.0, 0.2, 0.35, 0.7, 0.0),
    (0.1, 0.2, 0.35, 0.7, 0.08),
    (0.4, 0.3, 0.5, 0.9, 0.2),
    (0.5, 1.0, 0.85, 0.5, 0.9),
    (0.6, 0.9, 0.6, 0.3, 0.0),
    (1.0, 0.9, 0.6, 0.3, 0.0),
];

/// A built-in transfer function by name (see [`PRESETS`]).
pub fn preset(name: &str) -> Result<TransferFunction, DataError> {
    let points = match name {
        "phantom" => PHANTOM,
        "ct-skin-bone" | "ct" => CT_SKIN_BONE,
        "ct-bone" => CT_BONE,
        "mri" => MRI,
        "grey" | "gray" => GREY,
        "shells" => SHELLS,
        "level-set" => LEVEL_SET,
        other => {
            return Err(DataError::UnknownPreset {
                name: other.to_string(),
                known: PRESETS.join(", "),
            })
        }
    };
    let colors: Vec<(f32, [f32; 3])> = points
        .iter()
        .map(|&(x, r, g, b, _)| (x, [r, g, b]))
        .collect();
    let opacities: Vec<(f32, f32)> = points.iter().map(|&(x, .., o)| (x, o)).collect();
    Ok(tabulate(&colors, &opacities)?)
}

/// Resamples piecewise-linear color and opacity control points (value in
/// [0, 1], sorted by value; held constant beyond the ends) onto evenly
/// spaced tables over [0, 1].
pub(crate) fn tabulate(
    colors: &[(f32, [f32; 3])],
    opacities: &[(f32, f32)],
) -> Result<TransferFunction, TransferFunctionError> {
    if colors.is_empty() || opacities.is_empty() {
        return Err(TransferFunctionError::Empty);
    }
    let ts = (0..TABLE_SIZE).map(|i| i as f32 / (TABLE_SIZE - 1) as f32);
    TransferFunction::new(
        ts.clone()
            .map(|t| {
                let [r, g, b] = [0, 1, 2].map(|k| piecewise_linear(colors, t, |c| c[k]));
                Vec4::new(r, g, b, 1.0)
            })
            .collect(),
        ts.map(|t| piecewise_linear(opacities, t, |o| *o)).collect(),
        (0.0, 1.0),
        1.0,
    )
}

fn piecewise_linear<T>(points: &[(f32, T)], t: f32, get: impl Fn(&T) -> f32) -> f32 {
    let i = points.partition_point(|p| p.0 <= t);
    if i == 0 {
        return get(&points[0].1);
    }
    if i == points.len() {
        return get(&points[i - 1].1);
    }
    let ((x0, a), (x1, b)) = (&points[i - 1], &points[i]);
    let f = if x1 > x0 { (t - x0) / (x1 - x0) } else { 0.0 };
    get(a) + (get(b) - get(a)) * f
}
