//! The reference ray caster: the model of DESIGN.md section 4 written
//! plainly, one rayon task per image row. Tests hold the GPU to it, and
//! the tool falls back to it where no adapter exists.

mod march;
mod sample;

use rayon::prelude::*;

use super::frame::{linear_to_srgb, to_unorm8, ColorData, ColorFormat, Frame, FrameDesc};
use super::plan::{MarchPlan, Scene};
use super::{RenderError, RenderSettings};
use crate::geometry::RayGen;

pub(crate) use march::SHADOW_AMBIENT;

#[derive(Debug, Default)]
pub struct CpuRenderer;

impl CpuRenderer {
    pub fn new() -> Self {
        Self
    }

    pub fn render(
        &self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
    ) -> Result<Frame, RenderError> {
        desc.validate()?;
        let plan = MarchPlan::new(scene, settings)?;
        let field = sample::Field::new(&plan, &scene.volume, scene.transfer_function.table());
        let w = desc.size.x as usize;
        let mut color = vec![0.0f32; 4 * desc.pixels()];
        let mut depth = vec![0.0f32; desc.pixels()];
        let samples: u64 = color
            .par_chunks_mut(4 * w)
            .zip(depth.par_chunks_mut(w))
            .enumerate()
            .map(|(y, (crow, drow))| {
                let mut samples = 0u64;
                for x in 0..w {
                    let (o, d) = rays.pixel_ray(x as u32, y as u32);
                    let ray = march::march(&field, o, d);
                    crow[4 * x..4 * x + 4].copy_from_slice(&ray.color.to_array());
                    drow[x] = ray.depth;
                    samples += u64::from(ray.samples);
                }
                samples
            })
            .sum();
        let encode = |srgb: bool| {
            color
                .chunks_exact(4)
                .flat_map(|c| {
                    let rgb = |x: f32| if srgb { linear_to_srgb(x) } else { x };
                    [rgb(c[0]), rgb(c[1]), rgb(c[2]), c[3]].map(to_unorm8)
                })
                .collect()
        };
        let color = match desc.color {
            ColorFormat::Rgba8 => ColorData::Rgba8(encode(false)),
            ColorFormat::Srgba8 => ColorData::Srgba8(encode(true)),
            ColorFormat::Rgba32F => ColorData::Rgba32F(color),
        };
        Ok(Frame {
            size: desc.size,
            color,
            depth: desc.depth.then_some(depth),
            samples,
        })
    }
}
