//! A view as warps need it, on the GPU (shaders/capture.wgsl): the ray
//! caster's march through volumes and surfaces with each contributing
//! sample and surface recorded into the pixel's emission-absorption
//! layers, cast in bands like a frame.

use glam::{UVec2, Vec4};

use super::bindings::{binding_table, Kind};
use super::context::{unprepared, Context, Pass};
use super::raycast::RaycastPass;
use super::resources::floats;
use super::variant::{Keyed, SceneKey, Uses};
use crate::render::frame::Frame;
use crate::render::warp::Layer;
use crate::render::{FrameDesc, RenderError, RenderSettings, Watch};
use crate::scene::Scene;

binding_table! {
    /// Group 1 of the capture pass (group 0 is the ray caster's, group 2
    /// its band).
    CaptureResources / CaptureLayout = "capture_bindings" imports [] () {
        /// Two vec4s a layer (color; start, end, 1 for a surface's),
        /// `capture.x` layers a pixel.
        layer_out: Kind::storage_rw("array<vec4f>"),
        /// x: the layer count a pixel; y: a surface layer's depth (f32
        /// bits).
        capture: Kind::storage("vec4u"),
    }
}

pub(super) struct CapturePass {
    layout: CaptureLayout,
    pipelines: Keyed,
    /// The layer count a pixel (x) and a surface layer's depth (y).
    uniform: wgpu::Buffer,
    /// Layer buffers of `bytes` and the group binding them.
    buffers: Option<(u64, wgpu::Buffer, wgpu::Buffer, wgpu::BindGroup)>,
}

impl CapturePass {
    pub fn new(ctx: &Context, raycast: &RaycastPass) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let layout = CaptureLayout::new(device);
        let pipelines = Keyed::new(
            ("capture", "capture", "main"),
            &[
                raycast.volume_layout.group(),
                layout.group(),
                raycast.band_layout.group(),
            ],
            Uses::ALL,
            &[],
        );
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("capture"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self {
            layout,
            pipelines,
            uniform,
            buffers: None,
        })
    }

    /// Casts the frame the ray caster's uniforms describe (bound by
    /// `raycast`), keeping `layers` layers a pixel, surfaces
    /// `surface_depth` deep (the layer buffers hold `bytes`): the frame,
    /// its layers and the pass's milliseconds.
    #[allow(clippy::too_many_arguments)]
    pub fn capture(
        &mut self,
        ctx: &Context,
        raycast: &RaycastPass,
        scene: &Scene,
        settings: &RenderSettings,
        desc: &FrameDesc,
        (layers, surface_depth): (usize, f32),
        bytes: u64,
        watch: Watch,
    ) -> Result<(Frame, Vec<Layer>, f64), RenderError> {
        let size = desc.size;
        let pixels = u64::from(size.x) * u64::from(size.y);
        let bands = raycast.write_bands(ctx, size);
        watch.expect(bands.len() as u64);
        self.reserve(ctx, bytes);
        let (_, layer_buffer, layer_read, group) = self.buffers.as_ref().ok_or_else(unprepared)?;
        ctx.queue.write_buffer(
            &self.uniform,
            0,
            bytemuck::cast_slice(&[layers as u32, surface_depth.to_bits(), 0, 0]),
        );
        let main = raycast.group()?;
        let pass = Pass {
            pipeline: self
                .pipelines
                .get(ctx, SceneKey::of(ctx, scene, settings)?)?,
            groups: &[main, group],
            band: Some(&raycast.band_group),
        };
        let ms = ctx.dispatch_bands(&pass, &bands, watch)?;
        let frame = raycast.read_frame(ctx, desc, scene)?;
        let kept = if layers > 0 {
            let used = pixels * layers as u64 * 32;
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(layer_buffer, 0, layer_read, 0, used);
            ctx.queue.submit([encoder.finish()]);
            floats(&ctx.read(layer_read, used)?)
                .chunks_exact(8)
                .map(|l| Layer {
                    color: Vec4::from_slice(&l[..4]),
                    start: l[4],
                    end: l[5],
                    surface: l[6] != 0.0,
                })
                .collect()
        } else {
            Vec::new()
        };
        ctx.check()?;
        Ok((frame, kept, ms))
    }

    /// Layer buffers of at least `bytes`.
    fn reserve(&mut self, ctx: &Context, bytes: u64) {
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
        let group = CaptureResources {
            layer_out: layers.as_entire_binding(),
            capture: self.uniform.as_entire_binding(),
        }
        .bind(&ctx.device, &self.layout);
        self.buffers = Some((bytes, layers, read, group));
    }
}

/// Layer bytes of a capture of `size` with `layers` layers a pixel.
pub(super) fn layer_bytes(size: UVec2, layers: usize) -> u64 {
    let pixels = u64::from(size.x) * u64::from(size.y);
    (pixels * layers.max(1) as u64).saturating_mul(32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu::bindings::assert_declared;
    use crate::render::gpu::raycast::{BandLayout, VolumeLayout};
    use crate::render::gpu::shaders::compose;

    #[test]
    fn the_capture_shader_declares_its_tables() {
        for filterable in [false, true] {
            let groups = [
                &VolumeLayout::table(filterable),
                &CaptureLayout::table(),
                &BandLayout::table(),
            ];
            assert_declared(&compose("capture", &groups).unwrap(), &groups);
        }
    }
}
