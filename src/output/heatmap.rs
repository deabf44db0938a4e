//! Per-window DSSIM as a picture: where two images differ, and how much.

use image::{Rgba, RgbaImage};

use crate::render::SsimMap;

/// Each SSIM window's DSSIM `(1 - SSIM) / 2` as a block of
/// `stride` x `stride` pixels of `width` x `height`, colored black (0)
/// through red and yellow to white (`full_scale` or more). Rows are
/// flipped so the picture is upright like the frames' PNGs.
pub fn dssim_heatmap(map: &SsimMap, width: u32, height: u32, full_scale: f64) -> RgbaImage {
    let mut image = RgbaImage::from_pixel(width, height, Rgba([0, 0, 0, 255]));
    let s = map.stride;
    for wy in 0..map.windows.y {
        for wx in 0..map.windows.x {
            let ssim = map.values[(wy * map.windows.x + wx) as usize];
            let t = ((1.0 - ssim) / 2.0 / full_scale).clamp(0.0, 1.0);
            let color = hot(t);
            for y in wy * s..((wy + 1) * s).min(height) {
                for x in wx * s..((wx + 1) * s).min(width) {
                    image.put_pixel(x, height - 1 - y, color);
                }
            }
        }
    }
    image
}

/// Black, red, yellow, white along t in [0, 1].
fn hot(t: f64) -> Rgba<u8> {
    let ramp = |lo: f64| ((t - lo) * 3.0).clamp(0.0, 1.0);
    let byte = |v: f64| (v * 255.0).round() as u8;
    Rgba([
        byte(ramp(0.0)),
        byte(ramp(1.0 / 3.0)),
        byte(ramp(2.0 / 3.0)),
        255,
    ])
}

/// Images side by side on a dark grey strip, top-aligned.
pub fn side_by_side(images: &[&RgbaImage], gap: u32) -> RgbaImage {
    let width = images.iter().map(|i| i.width()).sum::<u32>()
        + gap * (images.len() as u32).saturating_sub(1);
    let height = images.iter().map(|i| i.height()).max().unwrap_or(0);
    let mut out = RgbaImage::from_pixel(width.max(1), height.max(1), Rgba([40, 40, 40, 255]));
    let mut x0 = 0;
    for image in images {
        image::imageops::overlay(&mut out, *image, i64::from(x0), 0);
        x0 += image.width() + gap;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::UVec2;

    #[test]
    fn identical_windows_are_black_and_full_scale_is_white() {
        let map = SsimMap {
            windows: UVec2::new(2, 1),
            stride: 4,
            values: vec![1.0, 1.0 - 2.0 * 0.1],
        };
        let image = dssim_heatmap(&map, 8, 4, 0.1);
        assert_eq!(image.get_pixel(0, 0), &Rgba([0, 0, 0, 255]));
        assert_eq!(image.get_pixel(7, 3), &Rgba([255, 255, 255, 255]));
        assert_eq!(hot(0.5), Rgba([255, 128, 0, 255]));
    }
}
