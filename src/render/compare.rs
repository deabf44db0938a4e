use glam::{UVec2, Vec4};

use super::{Frame, RenderError};

/// Side of the square windows SSIM is computed over.
pub const SSIM_WINDOW: u32 = 8;

// Wang et al.'s constants for a dynamic range of 1.
const C1: f64 = 0.01 * 0.01;
const C2: f64 = 0.03 * 0.03;

/// Per-window SSIM of two frames: one value per 8x8 window (windows
/// overlap by half), averaged over the RGB channels, lower-left first.
#[derive(Clone, Debug, PartialEq)]
pub struct SsimMap {
    pub windows: UVec2,
    /// Pixel offset between neighbouring windows.
    pub stride: u32,
    pub values: Vec<f64>,
}

impl SsimMap {
    pub fn mean(&self) -> f64 {
        self.values.iter().sum::<f64>() / self.values.len() as f64
    }
    pub fn min(&self) -> f64 {
        self.values.iter().copied().fold(f64::INFINITY, f64::min)
    }
}

/// Structural similarity of two frames of the same size, on linear RGB
/// premultiplied over their backgrounds (as displayed). Frames must have
/// the same size, at least one window.
pub fn ssim_map(a: &Frame, b: &Frame) -> Result<SsimMap, RenderError> {
    if a.size != b.size {
        return Err(RenderError::Settings(format!(
            "SSIM needs frames of the same size, got {}x{} and {}x{}",
            a.size.x, a.size.y, b.size.x, b.size.y
        )));
    }
    if a.size.min_element() < SSIM_WINDOW {
        return Err(RenderError::Settings(format!(
            "SSIM needs frames of at least {SSIM_WINDOW}x{SSIM_WINDOW}, got {}x{}",
            a.size.x, a.size.y
        )));
    }
    let (pa, pb) = (a.to_linear(), b.to_linear());
    let stride = SSIM_WINDOW / 2;
    let windows = (a.size - UVec2::splat(SSIM_WINDOW)) / stride + UVec2::ONE;
    let mut values = Vec::with_capacity((windows.x * windows.y) as usize);
    for wy in 0..windows.y {
        for wx in 0..windows.x {
            let at = |p: &[Vec4], x: u32, y: u32| p[(y * a.size.x + x) as usize];
            let mut sum = 0.0;
            for channel in 0..3 {
                let mut s = [0.0f64; 5];
                for y in wy * stride..wy * stride + SSIM_WINDOW {
                    for x in wx * stride..wx * stride + SSIM_WINDOW {
                        let u = f64::from(at(&pa, x, y)[channel]);
                        let v = f64::from(at(&pb, x, y)[channel]);
                        s[0] += u;
                        s[1] += v;
                        s[2] += u * u;
                        s[3] += v * v;
                        s[4] += u * v;
                    }
                }
                let n = f64::from(SSIM_WINDOW * SSIM_WINDOW);
                let (mu, mv) = (s[0] / n, s[1] / n);
                let var_u = (s[2] / n - mu * mu).max(0.0);
                let var_v = (s[3] / n - mv * mv).max(0.0);
                let cov = s[4] / n - mu * mv;
                sum += ((2.0 * mu * mv + C1) * (2.0 * cov + C2))
                    / ((mu * mu + mv * mv + C1) * (var_u + var_v + C2));
            }
            values.push(sum / 3.0);
        }
    }
    Ok(SsimMap {
        windows,
        stride,
        values,
    })
}

/// Mean SSIM over all windows (1 = identical).
pub fn ssim(a: &Frame, b: &Frame) -> Result<f64, RenderError> {
    Ok(ssim_map(a, b)?.mean())
}

/// Structural dissimilarity, `(1 - SSIM) / 2` (0 = identical).
pub fn dssim(a: &Frame, b: &Frame) -> Result<f64, RenderError> {
    Ok((1.0 - ssim(a, b)?) / 2.0)
}
