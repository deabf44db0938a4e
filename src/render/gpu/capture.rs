//! A view as warps need it, on the GPU (shaders/capture.wgsl): the ray
//! caster's march with each contributing sample recorded into the pixel's
//! emission-absorption layers, cast in bands like a frame.

use std::sync::atomic::AtomicBool;

use glam::{UVec2, Vec4};

use super::context::Pass;
use super::{
    bind_group, buffer_type, compute_pipeline_with, floats, layout_entry, shaders, unprepared,
    GpuRenderer, Variants,
};
use crate::geometry::RayGen;
use crate::render::frame::ColorData;
use crate::render::warp::{check_layers, Layer, Source};
use crate::render::{ColorFormat, FrameDesc, RenderError, RenderSettings};
use crate::scene::Scene;

pub(super) struct CaptureGpu {
    layout: wgpu::BindGroupLayout,
    exact: Variants,
    filtered: Option<Variants>,
    /// The layer count a pixel (x).
    uniform: wgpu::Buffer,
    /// Layer buffers of `bytes` and the group binding them.
    buffers: Option<(u64, wgpu::Buffer, wgpu::Buffer, wgpu::BindGroup)>,
}

impl GpuRenderer {
    /// `rays` cast for an image of `size` keeping `layers` layers a pixel
    /// (0: none), the background left out: what
    /// [`crate::render::CpuRenderer::capture`] makes, from the GPU. Returns
    /// the source and the pass's milliseconds (GPU timestamps where the
    /// adapter has them).
    pub fn capture(
        &mut self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        size: UVec2,
        layers: usize,
        stop: &AtomicBool,
    ) -> Result<(Source, f64), RenderError> {
        check_layers(layers)?;
        let desc = FrameDesc::new(size)
            .with_color(ColorFormat::Rgba32F)
            .with_depth();
        let settings = RenderSettings {
            background: Vec4::ZERO,
            background_image: None,
            ..settings.clone()
        };
        self.begin(scene, rays, &settings, &desc)?;
        let pixels = u64::from(size.x) * u64::from(size.y);
        let bytes = (pixels * layers.max(1) as u64).saturating_mul(32);
        if bytes > self.ctx.limits.max_storage_buffer_binding_size {
            return Err(RenderError::FrameTooLarge {
                size: size.to_array(),
                reason: format!(
                    "its {layers} layers a pixel take {bytes} bytes, more than one buffer holds"
                ),
                adapter: self.ctx.info.name.clone(),
            });
        }
        if self.capture.is_none() {
            self.capture = Some(CaptureGpu::new(self));
        }
        let bands = self.write_bands(size);
        if let Some(capture) = self.capture.as_mut() {
            capture.reserve(&self.ctx, bytes);
        }
        let capture = self.capture.as_ref().ok_or_else(unprepared)?;
        let (_, layer_buffer, layer_read, group) =
            capture.buffers.as_ref().ok_or_else(unprepared)?;
        self.ctx.queue.write_buffer(
            &capture.uniform,
            0,
            bytemuck::cast_slice(&[layers as u32, 0, 0, 0]),
        );
        let main = self.bind_group.as_ref().ok_or_else(unprepared)?;
        let pipeline = self.variant(&capture.exact, &capture.filtered, scene, &settings)?;
        let pass = Pass {
            pipeline,
            groups: &[main, group],
            band: Some(&self.band_group),
        };
        let ms = self.ctx.dispatch_bands(&pass, &bands, stop)?;
        self.last_pass_ms = ms;
        let frame = self.read_frame(&desc)?;
        let kept = if layers > 0 {
            let used = pixels * layers as u64 * 32;
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(layer_buffer, 0, layer_read, 0, used);
            self.ctx.queue.submit([encoder.finish()]);
            floats(&self.ctx.read(layer_read, used)?)
                .chunks_exact(8)
                .map(|l| Layer {
                    color: Vec4::from_slice(&l[..4]),
                    start: l[4],
                    end: l[5],
                })
                .collect()
        } else {
            Vec::new()
        };
        self.ctx.check()?;
        let (ColorData::Rgba32F(c), Some(depth)) = (frame.color, frame.depth) else {
            return Err(unprepared());
        };
        let color = c.chunks_exact(4).map(Vec4::from_slice).collect();
        Ok((
            Source::new(size, *rays, color, depth, kept, layers, frame.samples),
            ms,
        ))
    }
}

impl CaptureGpu {
    fn new(gpu: &GpuRenderer) -> Self {
        let device = &gpu.ctx.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("capture"),
            entries: &[
                layout_entry(
                    0,
                    buffer_type(wgpu::BufferBindingType::Storage { read_only: false }),
                ),
                layout_entry(1, buffer_type(wgpu::BufferBindingType::Uniform)),
            ],
        });
        let source = shaders::capture();
        let layouts = [&gpu.layout, &layout, &gpu.band_layout];
        let variant = |filtered: bool, one: bool| {
            let flag = |b: bool| if b { 1.0 } else { 0.0 };
            compute_pipeline_with(
                device,
                "capture",
                &source,
                &layouts,
                "main",
                &[("FILTERED", flag(filtered)), ("ONE_VOLUME", flag(one))],
            )
        };
        let exact = Variants {
            one: variant(false, true),
            several: variant(false, false),
        };
        let filtered = gpu.filtered.is_some().then(|| Variants {
            one: variant(true, true),
            several: variant(true, false),
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("capture"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            layout,
            exact,
            filtered,
            uniform,
            buffers: None,
        }
    }

    /// Layer buffers of at least `bytes`.
    fn reserve(&mut self, ctx: &super::context::Context, bytes: u64) {
        if self.buffers.as_ref().is_some_and(|b| b.0 >= bytes) {
            return;
        }
        let buffer = |label, usage| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(32),
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let layers = buffer("capture layers", U::STORAGE | U::COPY_SRC);
        let read = buffer("capture layers read-back", U::MAP_READ | U::COPY_DST);
        let group = bind_group(
            &ctx.device,
            "capture",
            &self.layout,
            [layers.as_entire_binding(), self.uniform.as_entire_binding()],
        );
        self.buffers = Some((bytes, layers, read, group));
    }
}
