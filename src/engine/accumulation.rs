//! Progressive refinement: a frame whose host set `accumulation` and
//! renders it again unchanged (OpenCOVER does, up to 64 times, the SDK's
//! viewer every frame it is idle) gets one more sample of each pixel's
//! area per render, its image the mean of them, up to [`MAX_SAMPLES`];
//! after that the image stands. The first sample is each pixel's centre,
//! the image a frame without accumulation shows; the others follow the R2
//! sequence over the pixel (Roberts 2018), whose every prefix covers it
//! evenly. Depth and the hit channels stay the first sample's: they say
//! what lies at the pixel's centre, where a host's own geometry is tested
//! against them.

use glam::{Vec2, Vec4};

use crate::render::{ColorData, ColorFormat, Frame, FrameDesc};

/// Samples a refined image takes at most.
pub const MAX_SAMPLES: u32 = 64;

/// Where sample `k` of each pixel lies, in pixels from its centre (each
/// coordinate in [-0.5, 0.5)); sample 0 is the centre.
pub fn subpixel(k: u32) -> Vec2 {
    if k == 0 {
        return Vec2::ZERO;
    }
    // The plastic number g: (1/g, 1/g^2) steps fill the square with the
    // lowest discrepancy of any additive recurrence.
    const G: f64 = 1.324_717_957_244_746;
    let at = |a: f64| ((0.5 + a * f64::from(k)).fract() - 0.5) as f32;
    Vec2::new(at(1.0 / G), at(1.0 / (G * G)))
}

/// The sum of a frame's samples, linear RGBA per pixel.
#[derive(Debug)]
pub struct Accumulated {
    sum: Vec<Vec4>,
    samples: u32,
}

impl Accumulated {
    /// The samples so far: the frame shown, standing for `samples` of them.
    pub fn new(shown: &Frame, samples: u32) -> Self {
        let n = samples.max(1) as f32;
        Self {
            sum: shown.to_linear().into_iter().map(|c| c * n).collect(),
            samples: samples.max(1),
        }
    }

    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Adds one more sample of every pixel, a frame of the same size.
    pub fn add(&mut self, sample: &Frame) -> Result<(), String> {
        if sample.size.x as usize * sample.size.y as usize != self.sum.len() {
            return Err(format!(
                "internal: a {}x{} sample for an image of {} pixels",
                sample.size.x,
                sample.size.y,
                self.sum.len()
            ));
        }
        for (acc, c) in self.sum.iter_mut().zip(sample.to_linear()) {
            *acc += c;
        }
        self.samples += 1;
        Ok(())
    }

    /// The mean of the samples in `shown`'s format, with `shown`'s depth
    /// and hits.
    pub fn image(&self, shown: &Frame) -> Result<Frame, String> {
        let format = match shown.color {
            ColorData::Rgba8(_) => ColorFormat::Rgba8,
            ColorData::Srgba8(_) => ColorFormat::Srgba8,
            ColorData::Rgba32F(_) => ColorFormat::Rgba32F,
        };
        let n = self.samples as f32;
        let mean: Vec<f32> = self.sum.iter().flat_map(|c| (*c / n).to_array()).collect();
        let desc = FrameDesc::new(shown.size).with_color(format);
        let mut image =
            Frame::from_linear(&desc, mean, shown.depth.clone()).map_err(|e| e.to_string())?;
        image.hits = shown.hits.clone();
        image.samples = shown.samples;
        Ok(image)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::UVec2;

    #[test]
    fn the_samples_cover_the_pixel_evenly_and_begin_at_its_centre() {
        assert_eq!(subpixel(0), Vec2::ZERO);
        let points: Vec<Vec2> = (0..MAX_SAMPLES).map(subpixel).collect();
        assert!(points
            .iter()
            .all(|p| p.cmpge(Vec2::splat(-0.5)).all() && p.cmplt(Vec2::splat(0.5)).all()));
        // Every quarter of the pixel holds about a quarter of the samples,
        // and the mean lies near the centre.
        for (sx, sy) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
            let n = points
                .iter()
                .filter(|p| p.x * sx >= 0.0 && p.y * sy >= 0.0)
                .count();
            assert!((12..=20).contains(&n), "quarter ({sx}, {sy}): {n} samples");
        }
        let mean = points.iter().sum::<Vec2>() / points.len() as f32;
        assert!(mean.length() < 0.04, "mean {mean}");
    }

    #[test]
    fn the_image_is_the_mean_of_the_samples_in_the_shown_format() {
        let desc = FrameDesc::new(UVec2::new(2, 1)).with_color(ColorFormat::Rgba8);
        let shown =
            Frame::from_linear(&desc, vec![1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], None).unwrap();
        let mut acc = Accumulated::new(&shown, 1);
        let float = FrameDesc::new(UVec2::new(2, 1)).with_color(ColorFormat::Rgba32F);
        let sample =
            Frame::from_linear(&float, vec![0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0], None).unwrap();
        acc.add(&sample).unwrap();
        assert_eq!(acc.samples(), 2);
        let image = acc.image(&shown).unwrap();
        assert_eq!(
            image.color,
            ColorData::Rgba8(vec![128, 0, 0, 255, 0, 128, 0, 255])
        );
        let wrong = Frame::from_linear(&FrameDesc::new(UVec2::ONE), vec![0.0; 4], None);
        assert!(acc.add(&wrong.unwrap()).is_err());
    }
}
