//! The ANARI conformance tool's image score, from its published rules:
//! both images composited over white and rounded to 8 bits, SSIM over 7 x 7
//! box windows (sample covariance, edges reflected, the border a window
//! cannot cover left out) averaged over R, G and B, and PSNR over the
//! three channels. A case passes at SSIM >= 0.7 and PSNR >= 20 dB.

pub const MIN_SSIM: f64 = 0.7;
pub const MIN_PSNR: f64 = 20.0;

/// (SSIM, PSNR in dB) of `candidate` against `reference`: RGBA8 images of
/// `w` x `h`. PSNR is infinite for identical images.
pub fn score(reference: &[u8], candidate: &[u8], w: usize, h: usize) -> (f64, f64) {
    assert_eq!(reference.len(), 4 * w * h);
    assert_eq!(candidate.len(), 4 * w * h);
    let over_white = |img: &[u8], c: usize| -> Vec<f64> {
        img.chunks_exact(4)
            .map(|p| {
                let (v, a) = (f64::from(p[c]), f64::from(p[3]));
                (v * a / 255.0 + (255.0 - a)).round().clamp(0.0, 255.0)
            })
            .collect()
    };
    let (mut ssim, mut squared) = (0.0, 0.0);
    for c in 0..3 {
        let (x, y) = (over_white(reference, c), over_white(candidate, c));
        ssim += ssim_channel(&x, &y, w, h) / 3.0;
        squared += x
            .iter()
            .zip(&y)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>();
    }
    let mse = squared / (3 * w * h) as f64;
    (ssim, 10.0 * (255.0 * 255.0 / mse).log10())
}

fn ssim_channel(x: &[f64], y: &[f64], w: usize, h: usize) -> f64 {
    const WIN: usize = 7;
    let (c1, c2) = ((0.01f64 * 255.0).powi(2), (0.03f64 * 255.0).powi(2));
    let n = (WIN * WIN) as f64;
    let sample = n / (n - 1.0);
    let product =
        |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(p, q)| p * q).collect() };
    let (ux, uy) = (box_mean(x, w, h, WIN), box_mean(y, w, h, WIN));
    let uxx = box_mean(&product(x, x), w, h, WIN);
    let uyy = box_mean(&product(y, y), w, h, WIN);
    let uxy = box_mean(&product(x, y), w, h, WIN);
    let pad = WIN / 2;
    let (mut sum, mut count) = (0.0, 0usize);
    for j in pad..h - pad {
        for i in pad..w - pad {
            let k = j * w + i;
            let vx = sample * (uxx[k] - ux[k] * ux[k]);
            let vy = sample * (uyy[k] - uy[k] * uy[k]);
            let vxy = sample * (uxy[k] - ux[k] * uy[k]);
            sum += (2.0 * ux[k] * uy[k] + c1) * (2.0 * vxy + c2)
                / ((ux[k] * ux[k] + uy[k] * uy[k] + c1) * (vx + vy + c2));
            count += 1;
        }
    }
    sum / count as f64
}

/// The mean over a `win`-wide box around each pixel, rows then columns,
/// with the edge pixels mirrored (index -1 reads 0).
fn box_mean(v: &[f64], w: usize, h: usize, win: usize) -> Vec<f64> {
    let r = (win / 2) as isize;
    let mirror = |i: isize, n: usize| -> usize {
        let n = n as isize;
        let mut i = i;
        while i < 0 || i >= n {
            i = if i < 0 { -i - 1 } else { 2 * n - i - 1 };
        }
        i as usize
    };
    let mut rows = vec![0.0; v.len()];
    for j in 0..h {
        for i in 0..w {
            rows[j * w + i] = (-r..=r)
                .map(|k| v[j * w + mirror(i as isize + k, w)])
                .sum::<f64>()
                / win as f64;
        }
    }
    let mut out = vec![0.0; v.len()];
    for j in 0..h {
        for i in 0..w {
            out[j * w + i] = (-r..=r)
                .map(|k| rows[mirror(j as isize + k, h) * w + i])
                .sum::<f64>()
                / win as f64;
        }
    }
    out
}
