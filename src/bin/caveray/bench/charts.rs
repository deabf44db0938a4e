//! What the two stereo benchmarks draw alike: the speed-up chart and the
//! DSSIM heat map of a re-projected eye against its own pass.

use std::path::Path;

use anari_library_caveray::output::{
    dssim_heatmap, frame_to_rgba, side_by_side, write_rgba_png, Chart, Series, XAxis,
};
use anari_library_caveray::render::{ssim_map, Frame};

use super::runtime;
use crate::Failure;

/// DSSIM shown white in the heat maps.
pub const HEATMAP_FULL_SCALE: f64 = 0.05;

/// V in percent, a line per series: from 100 % down to the lowest point,
/// in steps of 20 %.
pub fn speedup_chart(title: &str, x_label: &str, series: &[Series], x_axis: XAxis) -> String {
    let lowest = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .fold(0.0f64, f64::min);
    Chart {
        title,
        x_label,
        y_label: "V = 1 - (T_l+r - T_l) / T_r  [%]",
        y_range: ((lowest / 20.0).floor() * 20.0, 100.0),
        series,
        x_axis,
    }
    .to_svg()
}

/// Two-pass right image, re-projected right image, and their per-window
/// DSSIM, side by side.
pub fn heatmap(two_pass: &Frame, reprojected: &Frame, path: &Path) -> Result<(), Failure> {
    let map = ssim_map(reprojected, two_pass).map_err(runtime)?;
    let heat = dssim_heatmap(&map, two_pass.size.x, two_pass.size.y, HEATMAP_FULL_SCALE);
    let strip = side_by_side(
        &[&frame_to_rgba(two_pass), &frame_to_rgba(reprojected), &heat],
        8,
    );
    write_rgba_png(&strip, path).map_err(runtime)
}
