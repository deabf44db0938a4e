//! The re-projection stereo path on the GPU: the left eye ray cast with
//! its segments written into a texture array of layers
//! (shaders/reproject.wgsl), then the right eye composited from them
//! (shaders/composite.wgsl). Layers are never cleared: each left column
//! records the span of right pixels it wrote this frame, and compositing
//! reads nothing outside it.

use glam::UVec2;

use super::context::Context;
use super::uniforms::{Stereo, WORKGROUP};
use super::{
    bind_group, buffer_type, color_data, compute_pipeline, layout_entry, unprepared, GpuRenderer,
};
use crate::geometry::RayGen;
use crate::render::frame::{ColorFormat, Frame, FrameDesc};
use crate::render::stereo::{LayerFormat, Reprojection, StereoFrames, StereoTimes};
use crate::render::{RenderError, RenderSettings};
use crate::scene::Scene;

/// Pipelines for one layer format, and the resources of the last shape.
pub(super) struct StereoGpu {
    format: LayerFormat,
    reproject: wgpu::ComputePipeline,
    clear: wgpu::ComputePipeline,
    composite: wgpu::ComputePipeline,
    writer_layout: wgpu::BindGroupLayout,
    composite_layout: wgpu::BindGroupLayout,
    target: Option<LayerTarget>,
}

/// What identifies a set of layer resources. The left columns cast vary
/// from view to view; the spans buffer is sized for at least as many.
#[derive(Clone, Copy, PartialEq)]
struct Shape {
    size: UVec2,
    layers: u32,
    color: ColorFormat,
}

struct LayerTarget {
    shape: Shape,
    /// Left columns the spans buffer holds.
    columns: u32,
    uniform: wgpu::Buffer,
    view: wgpu::TextureView,
    color: wgpu::Buffer,
    color_read: wgpu::Buffer,
    writer: wgpu::BindGroup,
    composite: wgpu::BindGroup,
}

fn texture_format(format: LayerFormat) -> wgpu::TextureFormat {
    match format {
        LayerFormat::Rgba16F => wgpu::TextureFormat::Rgba16Float,
        LayerFormat::Rgba32F => wgpu::TextureFormat::Rgba32Float,
    }
}

impl StereoGpu {
    fn new(ctx: &Context, volume_layout: &wgpu::BindGroupLayout, format: LayerFormat) -> Self {
        let device = &ctx.device;
        let uniform = buffer_type(wgpu::BufferBindingType::Uniform);
        let writer_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("re-projection layers"),
            entries: &[
                layout_entry(0, uniform),
                layout_entry(
                    1,
                    wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: texture_format(format),
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                    },
                ),
                layout_entry(
                    2,
                    buffer_type(wgpu::BufferBindingType::Storage { read_only: false }),
                ),
            ],
        });
        let composite_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("compositing"),
            entries: &[
                layout_entry(0, uniform),
                layout_entry(
                    1,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                ),
                layout_entry(
                    2,
                    buffer_type(wgpu::BufferBindingType::Storage { read_only: true }),
                ),
                layout_entry(
                    3,
                    buffer_type(wgpu::BufferBindingType::Storage { read_only: false }),
                ),
            ],
        });
        let source = super::shaders::reproject(format);
        let writer = [volume_layout, &writer_layout];
        Self {
            format,
            reproject: compute_pipeline(device, "re-projection", &source, &writer, "main"),
            clear: compute_pipeline(device, "layer clear", &source, &writer, "clear"),
            composite: compute_pipeline(
                device,
                "compositing",
                &super::shaders::composite(),
                &[&composite_layout],
                "main",
            ),
            writer_layout,
            composite_layout,
            target: None,
        }
    }

    /// Makes the resources for `shape` and `columns` unless the last ones
    /// fit. A new texture costs a zero-fill on first use (wgpu's
    /// initialisation), so views that differ only in columns keep it and
    /// get a larger spans buffer, with room to spare.
    fn reshape(&mut self, ctx: &Context, shape: Shape, columns: u32) {
        let spare = columns + shape.size.x / 4;
        match self.target.take() {
            Some(t) if t.shape == shape && t.columns >= columns => self.target = Some(t),
            Some(t) if t.shape == shape => self.target = Some(t.with_spans(self, ctx, spare)),
            _ => self.target = Some(LayerTarget::new(self, ctx, shape, spare)),
        }
    }
}

impl LayerTarget {
    fn new(gpu: &StereoGpu, ctx: &Context, shape: Shape, columns: u32) -> Self {
        let device = &ctx.device;
        let layers = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("re-projection layers"),
            size: wgpu::Extent3d {
                width: shape.size.x,
                height: shape.size.y,
                depth_or_array_layers: shape.layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: texture_format(gpu.format),
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        // An explicit array view: with one layer the default would be 2D.
        let view = layers.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        use wgpu::BufferUsages as U;
        let uniform = buffer(
            ctx,
            "stereo",
            size_of::<Stereo>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let color_bytes =
            u64::from(shape.size.x) * u64::from(shape.size.y) * shape.color.bytes_per_pixel();
        let color = buffer(ctx, "right colour", color_bytes, U::STORAGE | U::COPY_SRC);
        let color_read = buffer(
            ctx,
            "right read-back",
            color_bytes,
            U::MAP_READ | U::COPY_DST,
        );
        let spans = spans_buffer(ctx, shape, columns);
        let (writer, composite) = bind_groups(gpu, ctx, &uniform, &view, &spans, &color);
        Self {
            shape,
            columns,
            uniform,
            view,
            color,
            color_read,
            writer,
            composite,
        }
    }

    /// The same layers with a spans buffer for `columns` left columns.
    fn with_spans(self, gpu: &StereoGpu, ctx: &Context, columns: u32) -> Self {
        let spans = spans_buffer(ctx, self.shape, columns);
        let (writer, composite) =
            bind_groups(gpu, ctx, &self.uniform, &self.view, &spans, &self.color);
        Self {
            columns,
            writer,
            composite,
            ..self
        }
    }
}

fn buffer(ctx: &Context, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}

fn spans_buffer(ctx: &Context, shape: Shape, columns: u32) -> wgpu::Buffer {
    let bytes = 8 * u64::from(columns) * u64::from(shape.size.y);
    buffer(ctx, "spans", bytes, wgpu::BufferUsages::STORAGE)
}

/// The re-projection pass's group 1 and the compositing pass's group 0.
fn bind_groups(
    gpu: &StereoGpu,
    ctx: &Context,
    uniform: &wgpu::Buffer,
    view: &wgpu::TextureView,
    spans: &wgpu::Buffer,
    color: &wgpu::Buffer,
) -> (wgpu::BindGroup, wgpu::BindGroup) {
    let device = &ctx.device;
    let writer = bind_group(
        device,
        "re-projection layers",
        &gpu.writer_layout,
        [
            uniform.as_entire_binding(),
            wgpu::BindingResource::TextureView(view),
            spans.as_entire_binding(),
        ],
    );
    let composite = bind_group(
        device,
        "compositing",
        &gpu.composite_layout,
        [
            uniform.as_entire_binding(),
            wgpu::BindingResource::TextureView(view),
            spans.as_entire_binding(),
            color.as_entire_binding(),
        ],
    );
    (writer, composite)
}

impl GpuRenderer {
    /// Fails, before touching the GPU, if the layers exceed what this
    /// adapter allows.
    fn check_layers(&self, r: &Reprojection) -> Result<(), RenderError> {
        let limits = &self.ctx.limits;
        let too_large = |reason: String| RenderError::FrameTooLarge {
            size: [r.size.x, r.size.y],
            reason,
            adapter: self.ctx.info.name.clone(),
        };
        if r.layers > limits.max_texture_array_layers {
            return Err(too_large(format!(
                "{} re-projection layers exceed the adapter's {} array layers",
                r.layers, limits.max_texture_array_layers
            )));
        }
        if r.size.max_element() > limits.max_texture_dimension_2d {
            return Err(too_large(format!(
                "the layers exceed the largest 2D texture ({} per side)",
                limits.max_texture_dimension_2d
            )));
        }
        let spans = 8 * u64::from(r.columns()) * u64::from(r.size.y);
        if spans > limits.max_storage_buffer_binding_size {
            return Err(too_large(format!(
                "its {spans} bytes of spans exceed the largest storage buffer"
            )));
        }
        if r.columns().div_ceil(WORKGROUP) > limits.max_compute_workgroups_per_dimension {
            return Err(too_large(format!(
                "{} left columns need too many workgroups",
                r.columns()
            )));
        }
        Ok(())
    }

    /// Both eyes from one ray casting pass: the left eye from `left`'s
    /// rays, the right eye re-projected from them as `reprojection` plans.
    /// The frame size is the plan's.
    pub fn render_reprojected(
        &mut self,
        scene: &Scene,
        left: &RayGen,
        reprojection: &Reprojection,
        settings: &RenderSettings,
        desc: &FrameDesc,
    ) -> Result<StereoFrames, RenderError> {
        desc.validate()?;
        if desc.size != reprojection.size {
            return Err(RenderError::Settings(format!(
                "the frame is {}x{} but the re-projection was planned for {}x{}",
                desc.size.x, desc.size.y, reprojection.size.x, reprojection.size.y
            )));
        }
        self.check_layers(reprojection)?;
        if settings.background_image.is_some() {
            return Err(RenderError::Settings(
                "re-projection composites over a flat background only; render background images in two passes".into(),
            ));
        }
        self.begin(scene, left, settings, desc)?;
        let ctx = &self.ctx;
        if !matches!(&self.stereo, Some(s) if s.format == reprojection.format) {
            self.stereo = Some(StereoGpu::new(ctx, &self.layout, reprojection.format));
        }
        let stereo = self.stereo.as_mut().ok_or_else(unprepared)?;
        let shape = Shape {
            size: desc.size,
            layers: reprojection.layers,
            color: desc.color,
        };
        let columns = reprojection.columns();
        stereo.reshape(ctx, shape, columns);
        let stereo = &*stereo;
        let target = stereo.target.as_ref().ok_or_else(unprepared)?;
        let uniform = Stereo::new(reprojection, desc.color, settings);
        ctx.queue
            .write_buffer(&target.uniform, 0, bytemuck::bytes_of(&uniform));
        let volume = self.bind_group.as_ref().ok_or_else(unprepared)?;
        let left_ms = ctx.dispatch(
            &stereo.reproject,
            &[volume, &target.writer],
            [
                columns.div_ceil(WORKGROUP),
                desc.size.y.div_ceil(WORKGROUP),
                1,
            ],
        )?;
        let composite_ms = ctx.dispatch(
            &stereo.composite,
            &[&target.composite],
            [
                desc.size.x.div_ceil(WORKGROUP),
                desc.size.y.div_ceil(WORKGROUP),
                1,
            ],
        )?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&target.color, 0, &target.color_read, 0, None);
        ctx.queue.submit([encoder.finish()]);
        let right = ctx.read(&target.color_read, target.color_read.size())?;
        let right = Frame {
            size: desc.size,
            color: color_data(desc.color, right),
            depth: None,
            samples: 0,
        };
        self.last_pass_ms = left_ms;
        let left = self.read_frame(desc)?;
        Ok(StereoFrames {
            left,
            right,
            times: StereoTimes {
                left_ms,
                composite_ms,
            },
        })
    }

    /// Milliseconds a full clear of the last frame's layers takes: the
    /// cost the span scheme avoids, for the benchmark to report.
    pub fn time_layer_clear(&mut self) -> Result<f64, RenderError> {
        let stereo = self.stereo.as_ref().ok_or_else(no_layers)?;
        let target = stereo.target.as_ref().ok_or_else(no_layers)?;
        let volume = self.bind_group.as_ref().ok_or_else(unprepared)?;
        let s = target.shape;
        self.ctx.dispatch(
            &stereo.clear,
            &[volume, &target.writer],
            [
                s.size.x.div_ceil(WORKGROUP),
                s.size.y.div_ceil(WORKGROUP),
                s.layers,
            ],
        )
    }
}

fn no_layers() -> RenderError {
    RenderError::Settings("no re-projection layers yet: render a re-projected frame first".into())
}
