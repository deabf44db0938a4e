//! The reference ray caster: the model of docs/ray_casting.md written
//! plainly, one rayon task per image row. Tests hold the GPU to it, and
//! the tool falls back to it where no adapter exists.

mod march;
mod sample;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use glam::Vec4;
use rayon::prelude::*;

use super::frame::{filled, linear_to_srgb, to_unorm8, ColorData, ColorFormat, Frame, FrameDesc};
use super::march_plan::MarchPlan;
use super::{RenderError, RenderSettings};
use crate::geometry::RayGen;
use crate::render::empty_space::SpaceCache;
use crate::scene::{Scene, StructuredVolume, TransferFunction};
use sample::Converted;

#[derive(Debug, Default)]
pub struct CpuRenderer {
    /// The last scene's voxels as f32 and its tables, kept while scenes
    /// bring the same `Arc`s, as the GPU keeps its uploads.
    cache: Mutex<Prepared>,
}

#[derive(Debug, Default)]
struct Prepared {
    values: Vec<(Arc<StructuredVolume>, Arc<Vec<f32>>)>,
    tables: Vec<(Arc<TransferFunction>, Arc<Vec<Vec4>>)>,
    spaces: SpaceCache,
}

impl CpuRenderer {
    pub fn new() -> Self {
        Self::default()
    }

    /// Each volume's values, table and (if the plan skips) clear bricks,
    /// made only when new.
    fn prepare(&self, scene: &Scene, plan: &MarchPlan) -> Result<Vec<Converted>, RenderError> {
        // A poisoned lock only means a panic elsewhere; the cache is rebuilt.
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        let spaces = if plan.skipping {
            cache
                .spaces
                .update(scene, plan)?
                .into_iter()
                .map(Some)
                .collect()
        } else {
            vec![None; scene.volumes().len()]
        };
        let mut next = Prepared {
            spaces: std::mem::take(&mut cache.spaces),
            ..Prepared::default()
        };
        let mut converted = Vec::new();
        for (placed, space) in scene.volumes().iter().zip(spaces) {
            let volume = &placed.volume;
            let values = match reuse(&cache.values, volume) {
                Some(v) => v,
                None => {
                    let voxels = volume.voxels();
                    let mut values = filled(voxels.len(), 0.0f32, "the volume as f32")?;
                    for (i, v) in values.iter_mut().enumerate() {
                        *v = voxels.value(i);
                    }
                    Arc::new(values)
                }
            };
            let tf = &placed.transfer_function;
            let table = reuse(&cache.tables, tf).unwrap_or_else(|| Arc::new(tf.table()));
            next.values.push((Arc::clone(volume), Arc::clone(&values)));
            next.tables.push((Arc::clone(tf), Arc::clone(&table)));
            converted.push(Converted {
                values,
                table,
                space,
            });
        }
        *cache = next;
        Ok(converted)
    }

    pub fn render(
        &self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
    ) -> Result<Frame, RenderError> {
        self.render_until(scene, rays, settings, desc, &AtomicBool::new(false))
    }

    /// `render`, casting no further pixel once `stop` is set and then
    /// returning `RenderError::Stopped`.
    pub fn render_until(
        &self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
        stop: &AtomicBool,
    ) -> Result<Frame, RenderError> {
        desc.validate()?;
        let plan = MarchPlan::new(scene, rays, settings)?;
        let data = self.prepare(scene, &plan)?;
        let field = sample::Field::new(&plan, &data);
        let w = desc.size.x as usize;
        let mut color = filled(4 * desc.pixels(), 0.0f32, "the frame's colour")?;
        let mut depth = filled(desc.pixels(), 0.0f32, "the frame's depth")?;
        let samples: u64 = color
            .par_chunks_mut(4 * w)
            .zip(depth.par_chunks_mut(w))
            .enumerate()
            .map(|(y, (crow, drow))| {
                let mut samples = 0u64;
                for x in 0..w {
                    // Per pixel: one slow row must not hold up a stop.
                    if stop.load(Ordering::Relaxed) {
                        return samples;
                    }
                    let (o, d) = rays.pixel_ray(x as u32, y as u32);
                    let bg = match &settings.background_image {
                        Some(image) => image.at(x as u32, y as u32, desc.size),
                        None => plan.background,
                    };
                    let ray = march::march(&field, rays, o, d, bg);
                    crow[4 * x..4 * x + 4].copy_from_slice(&ray.color.to_array());
                    drow[x] = ray.depth;
                    samples += u64::from(ray.samples);
                }
                samples
            })
            .sum();
        if stop.load(Ordering::Relaxed) {
            return Err(RenderError::Stopped);
        }
        let encode = |srgb: bool| -> Result<Vec<u8>, RenderError> {
            let mut out = filled(color.len(), 0u8, "the frame's 8-bit colour")?;
            for (o, c) in out.chunks_exact_mut(4).zip(color.chunks_exact(4)) {
                let rgb = |x: f32| if srgb { linear_to_srgb(x) } else { x };
                o.copy_from_slice(&[rgb(c[0]), rgb(c[1]), rgb(c[2]), c[3]].map(to_unorm8));
            }
            Ok(out)
        };
        let color = match desc.color {
            ColorFormat::Rgba8 => ColorData::Rgba8(encode(false)?),
            ColorFormat::Srgba8 => ColorData::Srgba8(encode(true)?),
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

/// What `cache` holds for `key`, if it holds it.
fn reuse<K, V>(cache: &[(Arc<K>, Arc<V>)], key: &Arc<K>) -> Option<Arc<V>> {
    cache
        .iter()
        .find(|(k, _)| Arc::ptr_eq(k, key))
        .map(|(_, v)| Arc::clone(v))
}
