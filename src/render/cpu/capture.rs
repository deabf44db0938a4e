//! A view as image warping needs it: color over nothing, first-hit depth
//! and the emission-absorption layers of its volumes and surfaces, cast
//! by the scalar path (layers are recorded per sample, which the packet
//! path does not visit).

use glam::{UVec2, Vec4};
use rayon::prelude::*;

use super::{march, sample, CpuRenderer};
use crate::geometry::RayGen;
use crate::render::frame::filled;
use crate::render::march_plan::MarchPlan;
use crate::render::warp::{check_layers, surface_layer_depth, Layer, LayerBuilder, Source};
use crate::render::{FrameDesc, RenderError, RenderSettings, Watch};
use crate::scene::Scene;

impl CpuRenderer {
    /// `rays` cast for an image of `size`, keeping `layers` layers per
    /// pixel (0: none, 1..=MAX_LAYERS). The background is left out: warps
    /// composite over it after they have moved the image. Counts rows.
    pub fn capture<'w>(
        &self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        size: UVec2,
        layers: usize,
        watch: impl Into<Watch<'w>>,
    ) -> Result<Source, RenderError> {
        let watch = watch.into();
        FrameDesc::new(size).validate()?;
        check_layers(layers)?;
        let plan = MarchPlan::new(scene, rays, settings)?;
        let shapes = self.shape_set(scene)?;
        let data = self.prepare(scene, &plan)?;
        let field = sample::Field::new(&plan, &data, None).with_shapes(shapes.as_deref());
        let surface_depth = surface_layer_depth(scene.bounds());
        let (w, n) = (size.x as usize, size.x as usize * size.y as usize);
        let mut color = filled(n, Vec4::ZERO, "the warp source's color")?;
        let mut depth = filled(n, f32::INFINITY, "the warp source's depth")?;
        // One layer a pixel at least, so that every row has its chunk.
        let per = layers.max(1);
        let mut kept = filled(n * per, Layer::default(), "the warp source's layers")?;
        watch.expect(u64::from(size.y));
        let samples: u64 = color
            .par_chunks_mut(w)
            .zip(depth.par_chunks_mut(w))
            .zip(kept.par_chunks_mut(w * per))
            .enumerate()
            .map(|(y, ((c, d), l))| {
                let mut samples = 0u64;
                for x in 0..w {
                    if watch.stopped() {
                        return samples;
                    }
                    let (o, dir) = rays.pixel_ray(x as u32, y as u32);
                    let mut builder = LayerBuilder::new(per, surface_depth);
                    let (color, depth, n) = match shapes.as_deref() {
                        None => {
                            let ray = march::march(
                                &field,
                                rays,
                                o,
                                dir,
                                (Vec4::ZERO, f32::INFINITY),
                                Some(&mut builder),
                            );
                            (ray.color, ray.depth, ray.samples)
                        }
                        Some(s) => {
                            let (color, depth, n, _) = super::through_surfaces(
                                s,
                                &field,
                                rays,
                                ((o, dir), None),
                                Vec4::ZERO,
                                settings,
                                Some(&mut builder),
                            );
                            (color, depth, n)
                        }
                    };
                    c[x] = color;
                    d[x] = depth;
                    if layers > 0 {
                        l[x * layers..(x + 1) * layers].copy_from_slice(builder.layers());
                    }
                    samples += u64::from(n);
                }
                watch.advance(1);
                samples
            })
            .sum();
        if watch.stopped() {
            return Err(RenderError::Stopped);
        }
        if layers == 0 {
            kept = Vec::new();
        }
        Ok(Source::new(
            size, *rays, color, depth, kept, layers, samples,
        ))
    }
}
