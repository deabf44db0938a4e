//! The re-projection stereo path on the GPU: the left eye ray cast with
//! its segments written into a texture array of layers
//! (shaders/reproject.wgsl), then the right eye composited from them
//! (shaders/composite.wgsl). Layers are never cleared: each left ray
//! records the span of right pixels it wrote this frame, and compositing
//! reads nothing outside it.

use std::sync::atomic::AtomicBool;

use glam::UVec2;
use wgpu::TextureViewDimension as Dim;

use super::bindings::{binding_table, GroupLayout, Kind};
use super::context::{unprepared, Context, Pass, WORKGROUP};
use super::raycast::RaycastPass;
use super::resources::{color_data, floats};
use super::shaders::compute_pipeline;
use super::uniforms::Stereo;
use super::variant::{Keyed, SceneKey, Uses};
use crate::render::frame::{ColorFormat, Frame, FrameDesc};
use crate::render::stereo::{LayerFormat, Reprojection, StereoTimes};
use crate::render::{RenderError, RenderSettings, Watch};
use crate::scene::Scene;

binding_table! {
    /// Group 1 of the re-projection pass (group 0 is the ray caster's).
    ReprojectResources / ReprojectLayout = "reproject_bindings" imports ["stereo_uniforms"]
        (format: wgpu::TextureFormat)
    {
        stereo: Kind::storage("Stereo"),
        layers: Kind::write_texture(Dim::D2Array, format),
        spans: Kind::storage_rw("array<vec4i>"),
        depths: Kind::write_texture(Dim::D2Array, wgpu::TextureFormat::Rgba32Float),
        /// Per right pixel, the right eye's first opaque surface from the
        /// composite's `first_opaque`: its color (xyz) and distance (w,
        /// infinite where there is none, negative where translucent
        /// surfaces lie in front of it).
        right_opaque: Kind::storage("array<vec4f>"),
    }
}

binding_table! {
    /// Group 1 of the compositing pass (group 0 is the ray caster's, for
    /// the right eye's surfaces).
    CompositeResources / CompositeLayout = "composite_bindings" imports ["stereo_uniforms"] () {
        stereo: Kind::storage("Stereo"),
        layers: Kind::texture(Dim::D2Array, false),
        spans: Kind::storage("array<vec4i>"),
        blocks: Kind::storage_rw("array<vec4i>"),
        right_color: Kind::storage_rw("array<u32>"),
        depths: Kind::texture(Dim::D2Array, false),
        right_depth: Kind::storage_rw("array<f32>"),
        right_opaque: Kind::storage_rw("array<vec4f>"),
    }
}

/// Pipelines for one layer format, and the resources of the last shape.
pub(super) struct LayersPass {
    format: LayerFormat,
    /// The left eye's march, writing one family of lines, and both, each
    /// compiled for its scenes' key when first needed.
    reproject: [Keyed; 2],
    clear: wgpu::ComputePipeline,
    /// The right eye's first opaque surfaces, before the march (worlds
    /// with surfaces only).
    first_opaque: Keyed,
    summarise: wgpu::ComputePipeline,
    composite: Keyed,
    /// The compositing without the block summary, to measure and check it.
    composite_every_offset: Keyed,
    writer_layout: ReprojectLayout,
    composite_layout: CompositeLayout,
    target: Option<LayerTarget>,
}

/// What a set of layer textures and right-eye buffers can hold. Walls of
/// a CAVE differ in their plans frame to frame; resources that hold a
/// plan are kept, since a new texture costs a zero-fill on first use
/// (wgpu's initialisation): the clear the span scheme exists to avoid.
#[derive(Clone, Copy, PartialEq)]
struct Shape {
    /// Right-eye pixels.
    pixels: u64,
    /// Texels of one layer.
    texels: UVec2,
    /// Layers of all families together.
    layers: u32,
    color: ColorFormat,
    /// Whether the layers record right-eye distances.
    depth: bool,
}

impl Shape {
    fn holds(&self, other: &Shape) -> bool {
        self.pixels >= other.pixels
            && self.texels.cmpge(other.texels).all()
            && self.layers >= other.layers
            && self.color == other.color
            && (self.depth || !other.depth)
    }

    /// Room for both, if that stays within twice the layer budget;
    /// else just `other`.
    fn grown(&self, other: &Shape, format: LayerFormat) -> Shape {
        if self.color != other.color {
            return *other;
        }
        let both = Shape {
            pixels: self.pixels.max(other.pixels),
            texels: self.texels.max(other.texels),
            layers: self.layers.max(other.layers),
            color: other.color,
            depth: self.depth || other.depth,
        };
        let bytes = crate::render::stereo::layer_memory(both.texels, both.layers, format);
        if bytes <= 2 * crate::render::stereo::LAYER_BUDGET {
            both
        } else {
            *other
        }
    }
}

struct LayerTarget {
    shape: Shape,
    /// Left pixels the spans buffer holds.
    cast: u64,
    res: Resources,
    writer: wgpu::BindGroup,
    composite: wgpu::BindGroup,
    /// The last frame's right eye, left pixels cast and scene key, if one
    /// was made.
    last: Option<(FrameDesc, UVec2, SceneKey)>,
}

/// Everything of a target but the spans and the bind groups.
struct Resources {
    uniform: wgpu::Buffer,
    layers: wgpu::TextureView,
    depths: wgpu::TextureView,
    color: wgpu::Buffer,
    color_read: wgpu::Buffer,
    depth: wgpu::Buffer,
    depth_read: wgpu::Buffer,
    right_opaque: wgpu::Buffer,
}

fn texture_format(format: LayerFormat) -> wgpu::TextureFormat {
    match format {
        LayerFormat::Rgba16F => wgpu::TextureFormat::Rgba16Float,
        LayerFormat::Rgba32F => wgpu::TextureFormat::Rgba32Float,
    }
}

impl LayersPass {
    pub fn new(
        ctx: &Context,
        raycast: &RaycastPass,
        format: LayerFormat,
    ) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let writer_layout = ReprojectLayout::new(device, texture_format(format));
        let composite_layout = CompositeLayout::new(device);
        // The march is cast in the ray caster's bands of rows (its band
        // group last), so that a discard stops it between bands.
        let writer = [
            raycast.volume_layout.group(),
            writer_layout.group(),
            raycast.band_layout.group(),
        ];
        let compositing = [raycast.volume_layout.group(), composite_layout.group()];
        let reproject = |both: bool| {
            Keyed::new(
                ("re-projection", "reproject", "main"),
                &writer,
                Uses::EXACT,
                &[("BOTH_FAMILIES", if both { 1.0 } else { 0.0 })],
            )
        };
        let surfaces = |label, entry, fixed: &[(&'static str, f64)]| {
            Keyed::new(
                (label, "composite", entry),
                &compositing,
                Uses::SURFACES,
                fixed,
            )
        };
        let plain = |label, module, entry, groups: &[&GroupLayout]| {
            compute_pipeline(device, label, module, entry, groups, &[("SURFACES", 0.0)])
        };
        Ok(Self {
            format,
            reproject: [reproject(false), reproject(true)],
            clear: plain("layer clear", "reproject", "clear", &writer)?,
            first_opaque: surfaces("right-eye surfaces", "first_opaque", &[]),
            summarise: plain("span blocks", "composite", "summarise", &compositing)?,
            composite: surfaces("compositing", "main", &[]),
            composite_every_offset: surfaces(
                "compositing every offset",
                "main",
                &[("EVERY_OFFSET", 1.0)],
            ),
            writer_layout,
            composite_layout,
            target: None,
        })
    }

    pub fn format(&self) -> LayerFormat {
        self.format
    }

    /// Makes resources for `shape` and `cast` left pixels unless the last
    /// ones hold them: views that need only more pixels cast get a larger
    /// spans buffer, others resources that hold both the old and the new
    /// shape, with room to spare.
    fn reshape(&mut self, ctx: &Context, shape: Shape, cast: u64) {
        let spare = cast + cast / 4;
        self.target = Some(match self.target.take() {
            Some(t) if t.shape.holds(&shape) && t.cast >= cast => t,
            Some(t) if t.shape.holds(&shape) => t.with_spans(self, ctx, spare),
            Some(t) => {
                let grown = t.shape.grown(&shape, self.format);
                drop(t);
                LayerTarget::new(self, ctx, grown, spare.max(cast))
            }
            None => LayerTarget::new(self, ctx, shape, spare),
        });
    }
}

fn array_texture(
    ctx: &Context,
    label: &str,
    size: UVec2,
    layers: u32,
    format: wgpu::TextureFormat,
) -> wgpu::TextureView {
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size.x,
            height: size.y,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    // An explicit array view: with one layer the default would be 2D.
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

impl LayerTarget {
    fn new(gpu: &LayersPass, ctx: &Context, shape: Shape, cast: u64) -> Self {
        let layers = array_texture(
            ctx,
            "re-projection layers",
            shape.texels,
            shape.layers,
            texture_format(gpu.format),
        );
        // Without a depth channel one texel stands in for the depths.
        let (depth_texels, depth_layers) = if shape.depth {
            (shape.texels, shape.layers)
        } else {
            (UVec2::ONE, 1)
        };
        let depths = array_texture(
            ctx,
            "re-projection depths",
            depth_texels,
            depth_layers,
            wgpu::TextureFormat::Rgba32Float,
        );
        use wgpu::BufferUsages as U;
        let uniform = buffer(
            ctx,
            "stereo",
            size_of::<Stereo>() as u64,
            U::STORAGE | U::COPY_DST,
        );
        let pixels = shape.pixels;
        let color_bytes = pixels * shape.color.bytes_per_pixel();
        let color = buffer(ctx, "right color", color_bytes, U::STORAGE | U::COPY_SRC);
        let color_read = buffer(
            ctx,
            "right read-back",
            color_bytes,
            U::MAP_READ | U::COPY_DST,
        );
        let depth_bytes = if shape.depth { 4 * pixels } else { 4 };
        let depth = buffer(ctx, "right depth", depth_bytes, U::STORAGE | U::COPY_SRC);
        let depth_read = buffer(
            ctx,
            "right depth read-back",
            depth_bytes,
            U::MAP_READ | U::COPY_DST,
        );
        let right_opaque = buffer(ctx, "right opaque surfaces", 16 * pixels, U::STORAGE);
        let res = Resources {
            right_opaque,
            uniform,
            layers,
            depths,
            color,
            color_read,
            depth,
            depth_read,
        };
        let (writer, composite) = bind_groups(gpu, ctx, &res, &Spans::new(ctx, cast));
        Self {
            shape,
            cast,
            res,
            writer,
            composite,
            last: None,
        }
    }

    /// The same layers with a spans buffer for `cast` left pixels.
    fn with_spans(self, gpu: &LayersPass, ctx: &Context, cast: u64) -> Self {
        let (writer, composite) = bind_groups(gpu, ctx, &self.res, &Spans::new(ctx, cast));
        Self {
            cast,
            writer,
            composite,
            last: None,
            ..self
        }
    }
}

/// The re-projection pass's group 1 and the compositing pass's group 0.
fn bind_groups(
    gpu: &LayersPass,
    ctx: &Context,
    res: &Resources,
    spans: &Spans,
) -> (wgpu::BindGroup, wgpu::BindGroup) {
    let device = &ctx.device;
    let writer = ReprojectResources {
        stereo: res.uniform.as_entire_binding(),
        layers: wgpu::BindingResource::TextureView(&res.layers),
        spans: spans.rays.as_entire_binding(),
        depths: wgpu::BindingResource::TextureView(&res.depths),
        right_opaque: res.right_opaque.as_entire_binding(),
    }
    .bind(device, &gpu.writer_layout);
    let composite = CompositeResources {
        stereo: res.uniform.as_entire_binding(),
        layers: wgpu::BindingResource::TextureView(&res.layers),
        spans: spans.rays.as_entire_binding(),
        blocks: spans.blocks.as_entire_binding(),
        right_color: res.color.as_entire_binding(),
        depths: wgpu::BindingResource::TextureView(&res.depths),
        right_depth: res.depth.as_entire_binding(),
        right_opaque: res.right_opaque.as_entire_binding(),
    }
    .bind(device, &gpu.composite_layout);
    (writer, composite)
}

fn buffer(ctx: &Context, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}

/// Four i32 per left pixel cast: the columns and the rows it wrote.
const SPAN_BYTES: u64 = 16;

/// What each left ray wrote, and the union over each block of
/// WORKGROUP x WORKGROUP rays (shaders/composite.wgsl).
struct Spans {
    rays: wgpu::Buffer,
    blocks: wgpu::Buffer,
}

impl Spans {
    /// Room for `cast` left pixels in any shape: an a x b image has at
    /// most (a + 7)(b + 7) / 64 <= ab / 8 + 1 blocks of 8 x 8.
    fn new(ctx: &Context, cast: u64) -> Self {
        let blocks = cast / u64::from(WORKGROUP) + 1;
        Self {
            rays: buffer(ctx, "spans", SPAN_BYTES * cast, wgpu::BufferUsages::STORAGE),
            blocks: buffer(
                ctx,
                "span blocks",
                SPAN_BYTES * blocks,
                wgpu::BufferUsages::STORAGE,
            ),
        }
    }
}

impl LayersPass {
    /// Fails, before touching the GPU, if the layers exceed what this
    /// adapter allows.
    pub fn check(ctx: &Context, r: &Reprojection) -> Result<(), RenderError> {
        let limits = &ctx.limits;
        let too_large = |reason: String| RenderError::FrameTooLarge {
            size: [r.size.x, r.size.y],
            reason,
            adapter: ctx.info.name.clone(),
        };
        let layers = r.layers * r.plan.family_count();
        if layers > limits.max_texture_array_layers {
            return Err(too_large(format!(
                "{layers} re-projection layers exceed the adapter's {} array layers",
                limits.max_texture_array_layers
            )));
        }
        if r.plan.texture_size().max_element() > limits.max_texture_dimension_2d {
            return Err(too_large(format!(
                "the layers exceed the largest 2D texture ({} per side)",
                limits.max_texture_dimension_2d
            )));
        }
        let cast = r.plan.cast;
        let spans = SPAN_BYTES * u64::from(cast.x) * u64::from(cast.y);
        if spans + spans / 4 > limits.max_storage_buffer_binding_size {
            return Err(too_large(format!(
                "its {spans} bytes of spans exceed the largest storage buffer"
            )));
        }
        if cast.max_element().div_ceil(WORKGROUP) > limits.max_compute_workgroups_per_dimension {
            return Err(too_large(format!(
                "{}x{} left pixels cast need too many workgroups",
                cast.x, cast.y
            )));
        }
        Ok(())
    }

    /// The right eye re-projected from the left eye's march (the ray
    /// caster's uniforms and group 0, as `raycast` bound them for the left
    /// eye) as `reprojection` plans: the right frame and both passes'
    /// milliseconds. Counts the march's bands and one unit for the
    /// compositing.
    pub fn render(
        &mut self,
        (ctx, raycast): (&Context, &RaycastPass),
        scene: &Scene,
        reprojection: &Reprojection,
        settings: &RenderSettings,
        desc: &FrameDesc,
        watch: Watch,
    ) -> Result<(Frame, StereoTimes), RenderError> {
        let plan = &reprojection.plan;
        let pixels = u64::from(desc.size.x) * u64::from(desc.size.y);
        let surfaces = !scene.shapes().is_empty();
        let shape = Shape {
            pixels,
            texels: plan.texture_size(),
            layers: reprojection.layers * plan.family_count(),
            color: desc.color,
            depth: desc.depth || surfaces,
        };
        let cast = plan.cast;
        self.reshape(ctx, shape, u64::from(cast.x) * u64::from(cast.y));
        let target = self.target.as_ref().ok_or_else(unprepared)?;
        let res = &target.res;
        let uniform = Stereo::new(reprojection, desc.color, settings, desc.depth, surfaces);
        ctx.queue
            .write_buffer(&res.uniform, 0, bytemuck::bytes_of(&uniform));
        let volume = raycast.group()?;
        let key = SceneKey::of(ctx, scene, settings)?;
        // Where the right eye's own surfaces end its view, for the march
        // behind the left eye's: a world without surfaces needs none.
        let first_opaque_ms = if surfaces {
            ctx.dispatch(
                self.first_opaque.get(ctx, key)?,
                &[volume, &target.composite],
                [
                    desc.size.x.div_ceil(WORKGROUP),
                    desc.size.y.div_ceil(WORKGROUP),
                    1,
                ],
            )?
        } else {
            0.0
        };
        let both = plan.family_count() == 2;
        let pipeline = self.reproject[usize::from(both)].get(ctx, key)?;
        let march = Pass {
            pipeline,
            groups: &[volume, &target.writer],
            band: Some(&raycast.band_group),
        };
        let bands = raycast.write_bands(ctx, cast);
        watch.expect(bands.len() as u64 + 1);
        let left_ms = first_opaque_ms + ctx.dispatch_bands(&march, &bands, watch)?;
        if watch.stopped() {
            return Err(RenderError::Stopped);
        }
        let (right, composite_ms) = self.composite_right((ctx, raycast), desc, cast, key, false)?;
        watch.advance(1);
        Ok((
            right,
            StereoTimes {
                left_ms,
                composite_ms,
            },
        ))
    }

    /// The right eye from the layers the march left, and its milliseconds
    /// (with the block summary's).
    fn composite_right(
        &mut self,
        (ctx, raycast): (&Context, &RaycastPass),
        desc: &FrameDesc,
        cast: UVec2,
        key: SceneKey,
        every_offset: bool,
    ) -> Result<(Frame, f64), RenderError> {
        let target = self.target.as_mut().ok_or_else(unprepared)?;
        target.last = Some((*desc, cast, key));
        let res = &target.res;
        let groups = [raycast.group()?, &target.composite];
        let summarise_ms = ctx.dispatch(
            &self.summarise,
            &groups,
            [
                cast.x.div_ceil(WORKGROUP * WORKGROUP),
                cast.y.div_ceil(WORKGROUP * WORKGROUP),
                1,
            ],
        )?;
        let pipeline = if every_offset {
            &self.composite_every_offset
        } else {
            &self.composite
        };
        let composite_ms = ctx.dispatch(
            pipeline.get(ctx, key)?,
            &groups,
            [
                desc.size.x.div_ceil(WORKGROUP),
                desc.size.y.div_ceil(WORKGROUP),
                1,
            ],
        )?;
        let pixels = u64::from(desc.size.x) * u64::from(desc.size.y);
        let (color_bytes, depth_bytes) = (pixels * desc.color.bytes_per_pixel(), 4 * pixels);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&res.color, 0, &res.color_read, 0, color_bytes);
        if desc.depth {
            encoder.copy_buffer_to_buffer(&res.depth, 0, &res.depth_read, 0, depth_bytes);
        }
        ctx.queue.submit([encoder.finish()]);
        let color = ctx.read(&res.color_read, color_bytes)?;
        let depth = if desc.depth {
            Some(floats(&ctx.read(&res.depth_read, depth_bytes)?))
        } else {
            None
        };
        let right = Frame {
            size: desc.size,
            color: color_data(desc.color, color),
            depth,
            hits: None,
            samples: 0,
        };
        Ok((right, summarise_ms + composite_ms))
    }

    /// The last right eye composited again, reading every left ray of the
    /// bounding depth range: what the block summary spares, for the
    /// benchmark to measure and the tests to check it changes nothing.
    pub fn composite_every_offset(
        &mut self,
        ctx: &Context,
        raycast: &RaycastPass,
    ) -> Result<(Frame, f64), RenderError> {
        let target = self.target.as_ref().ok_or_else(no_layers)?;
        let (desc, cast, key) = target.last.ok_or_else(no_layers)?;
        self.composite_right((ctx, raycast), &desc, cast, key, true)
    }

    /// Milliseconds a full clear of the last frame's layers takes: the
    /// cost the span scheme avoids, for the benchmark to report.
    pub fn time_clear(&self, ctx: &Context, raycast: &RaycastPass) -> Result<f64, RenderError> {
        let target = self.target.as_ref().ok_or_else(no_layers)?;
        let volume = raycast.group()?;
        let s = target.shape;
        // One band: the clear reads no band, but its pipeline binds one.
        let clear = Pass {
            pipeline: &self.clear,
            groups: &[volume, &target.writer],
            band: Some(&raycast.band_group),
        };
        let all = [
            s.texels.x.div_ceil(WORKGROUP),
            s.texels.y.div_ceil(WORKGROUP),
            s.layers,
        ];
        ctx.dispatch_bands(&clear, &[all], Watch::new(&AtomicBool::new(false)))
    }
}

pub(super) fn no_layers() -> RenderError {
    RenderError::Settings("no re-projection layers yet: render a re-projected frame first".into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu::bindings::assert_declared;
    use crate::render::gpu::raycast::{BandLayout, VolumeLayout};
    use crate::render::gpu::shaders::compose;

    #[test]
    fn the_stereo_shaders_declare_their_tables() {
        for format in [LayerFormat::Rgba16F, LayerFormat::Rgba32F] {
            let groups = [
                &VolumeLayout::table(false),
                &ReprojectLayout::table(texture_format(format)),
                &BandLayout::table(),
            ];
            assert_declared(&compose("reproject", &groups).unwrap(), &groups);
        }
        let groups = [&VolumeLayout::table(false), &CompositeLayout::table()];
        assert_declared(&compose("composite", &groups).unwrap(), &groups);
    }
}
