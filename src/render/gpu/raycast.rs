//! The ray casting pass (shaders/raycast.wgsl after volume.wgsl): one
//! invocation per pixel, cast in bands of rows. Its group 0 (the eye's
//! uniforms, the scene's textures and the frame's outputs) is also group
//! 0 of the capture and re-projection passes, which march the same way.

use crate::render::Watch;

use glam::UVec2;
use wgpu::TextureViewDimension as Dim;

use super::bindings::{binding_table, Kind};
use super::context::{unprepared, Context, Pass, BAND_STRIDE, WORKGROUP};
use super::resources::{color_data, floats, BrickSlot, OutputBuffers, SurfaceSlot};
use super::scene::GpuScene;
use super::uniforms::{self, RayUniforms};
use super::variant::{Keyed, SceneKey, Uses};
use super::volume_texture::TextureSlot;
use crate::geometry::RayGen;
use crate::render::frame::{Frame, FrameDesc};
use crate::render::hits::{self, HitRecord};
use crate::render::march_plan::MarchPlan;
use crate::render::settings::MAX_DIRECTIONS;
use crate::render::{RenderError, RenderSettings};
use crate::scene::Scene;

binding_table! {
    /// Group 0 of the passes that march volumes.
    VolumeResources / VolumeLayout = "volume_bindings" imports ["ray_uniforms"] (filterable: bool) {
        params: Kind::storage("RayUniforms"),
        /// Volume v's values; volumes 1 to 7 are bound after the other
        /// resources (a 1x1x1 stand-in where the scene has fewer), so WGSL
        /// needs no binding arrays, which not every adapter offers.
        volume0: Kind::texture(Dim::D3, filterable),
        /// Row v: volume v's table.
        table: Kind::texture(Dim::D2, filterable),
        directions: Kind::storage("array<vec4f>"),
        color_out: Kind::storage_rw("array<u32>"),
        depth_out: Kind::storage_rw("array<f32>"),
        /// Volume samples per pixel (primary and shading), summed on the
        /// host.
        samples_out: Kind::storage_rw("array<u32>"),
        background_image: Kind::texture(Dim::D2, filterable),
        volume1: Kind::texture(Dim::D3, filterable),
        volume2: Kind::texture(Dim::D3, filterable),
        volume3: Kind::texture(Dim::D3, filterable),
        volume4: Kind::texture(Dim::D3, filterable),
        volume5: Kind::texture(Dim::D3, filterable),
        volume6: Kind::texture(Dim::D3, filterable),
        volume7: Kind::texture(Dim::D3, filterable),
        /// Per brick of each volume, the chessboard distance (in bricks)
        /// to the nearest brick its table could make visible; volume v's
        /// from params.volumes[v].brick_offset on
        /// (src/render/empty_space.rs).
        bricks: Kind::storage("array<u32>"),
        /// The paged volumes' page tables (src/render/gpu/paging.rs);
        /// volume v's from params.volumes[v].page_offset on.
        pages: Kind::storage("array<u32>"),
        /// The unstructured volumes' cells, BVHs, positions and values
        /// (src/render/gpu/mesh.rs); volume v's from
        /// params.volumes[v].mesh_offset on.
        meshes: Kind::storage("array<u32>"),
        /// Linear where the adapter filters 32-bit floats (filtered
        /// sampling).
        linear: Kind::sampler(filterable),
        /// The same, blending between mip levels (level of detail).
        linear_mips: Kind::sampler(filterable),
        /// The world's surfaces: their BVH, primitives and shapes
        /// (render/shapes/packed.rs), where params.surface_* say.
        surfaces: Kind::storage("array<vec4f>"),
        /// Their per-primitive shading data and image texels.
        surface_shading: Kind::storage("array<vec4f>"),
    }
}

binding_table! {
    /// The group after a banded pass's others, bound at each band's
    /// dynamic offset.
    BandResources / BandLayout = "band_bindings" imports [] () {
        /// x: the first row of this band (the frame is cast a band of rows
        /// at a time, so a discard can stop it between bands); y: the
        /// stride its workgroups are dealt over it by (band.wgsl).
        band: Kind::dynamic_uniform("vec4u", 16),
    }
}

pub(super) struct RaycastPass {
    pub volume_layout: VolumeLayout,
    pub band_layout: BandLayout,
    pipelines: Keyed,
    /// Whether the adapter filters 32-bit floats (filtered sampling).
    filterable: bool,
    sampler: wgpu::Sampler,
    mip_sampler: wgpu::Sampler,
    params: wgpu::Buffer,
    directions: wgpu::Buffer,
    /// Each band's first row, BAND_STRIDE bytes apart, and the group that
    /// binds one of them.
    bands: wgpu::Buffer,
    pub band_group: wgpu::BindGroup,
    target: Option<OutputBuffers>,
    /// Group 0, and the scene generation it binds.
    group: Option<(u64, wgpu::BindGroup)>,
}

impl RaycastPass {
    pub fn new(ctx: &Context) -> Result<Self, RenderError> {
        let device = &ctx.device;
        // Filterable where the adapter filters 32-bit floats: then the
        // filtered pipeline reads the same textures through a sampler.
        let filterable = ctx.filterable;
        let volume_layout = VolumeLayout::new(device, filterable);
        let band_layout = BandLayout::new(device);
        let pipelines = Keyed::new(
            ("raycast", "raycast", "main"),
            &[volume_layout.group(), band_layout.group()],
            Uses::ALL,
            &[],
        );
        // Linear where the adapter filters 32-bit floats. Level of detail's
        // sampler blends mip levels too, so that it coarsens smoothly; full
        // detail keeps the other, which software Vulkan samples faster.
        let sampler = |label, mips: bool| {
            let (filter, mipmap_filter) = if filterable {
                let mipmap = if mips {
                    wgpu::MipmapFilterMode::Linear
                } else {
                    wgpu::MipmapFilterMode::Nearest
                };
                (wgpu::FilterMode::Linear, mipmap)
            } else {
                (wgpu::FilterMode::Nearest, wgpu::MipmapFilterMode::Nearest)
            };
            device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some(label),
                mag_filter: filter,
                min_filter: filter,
                mipmap_filter,
                ..Default::default()
            })
        };
        let mip_sampler = sampler("volume mip levels", true);
        let sampler = sampler("volumes and tables", false);
        let uniform = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let params = uniform(
            "params",
            size_of::<RayUniforms>() as u64,
            wgpu::BufferUsages::STORAGE,
        );
        let directions = uniform(
            "directions",
            16 * u64::from(MAX_DIRECTIONS),
            wgpu::BufferUsages::STORAGE,
        );
        let bands = uniform(
            "bands",
            u64::from(MAX_BANDS * BAND_STRIDE),
            wgpu::BufferUsages::UNIFORM,
        );
        let band_group = BandResources {
            band: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &bands,
                offset: 0,
                size: wgpu::BufferSize::new(16),
            }),
        }
        .bind(device, &band_layout);
        Ok(Self {
            filterable,
            volume_layout,
            band_layout,
            pipelines,
            sampler,
            mip_sampler,
            params,
            directions,
            bands,
            band_group,
            target: None,
            group: None,
        })
    }

    /// Whether this adapter runs filtered sampling.
    pub fn filters(&self) -> bool {
        self.filterable
    }

    /// Group 0 as the last `bind` made it.
    pub fn group(&self) -> Result<&wgpu::BindGroup, RenderError> {
        self.group.as_ref().map(|(_, g)| g).ok_or_else(unprepared)
    }

    /// Output buffers for a frame of `size` and `format`, and group 0
    /// binding them with what `scene` holds now; both made anew only
    /// where they changed.
    pub fn bind(&mut self, ctx: &Context, scene: &GpuScene, desc: &FrameDesc) {
        let mut changed = !matches!(&self.group, Some((g, _)) if *g == scene.generation());
        if !matches!(&self.target, Some(t) if t.fit(desc)) {
            self.target = Some(OutputBuffers::new(ctx, desc.size, desc.color, desc.hits));
            changed = true;
        }
        let Some(target) = self.target.as_ref().filter(|_| changed) else {
            return;
        };
        let volume = |i| wgpu::BindingResource::TextureView(scene.volume(i));
        let group = VolumeResources {
            params: self.params.as_entire_binding(),
            volume0: volume(0),
            table: wgpu::BindingResource::TextureView(scene.table_view()),
            directions: self.directions.as_entire_binding(),
            color_out: target.color.as_entire_binding(),
            depth_out: target.depth.as_entire_binding(),
            samples_out: target.samples.as_entire_binding(),
            background_image: wgpu::BindingResource::TextureView(scene.background()),
            volume1: volume(1),
            volume2: volume(2),
            volume3: volume(3),
            volume4: volume(4),
            volume5: volume(5),
            volume6: volume(6),
            volume7: volume(7),
            bricks: scene.bricks().as_entire_binding(),
            pages: scene.pages().as_entire_binding(),
            meshes: scene.meshes().as_entire_binding(),
            linear: wgpu::BindingResource::Sampler(&self.sampler),
            linear_mips: wgpu::BindingResource::Sampler(&self.mip_sampler),
            surfaces: scene.surfaces()[0].as_entire_binding(),
            surface_shading: scene.surfaces()[1].as_entire_binding(),
        }
        .bind(&ctx.device, &self.volume_layout);
        self.group = Some((scene.generation(), group));
    }

    /// Writes the uniforms for ray casting `rays` as `plan` and
    /// `settings` say.
    pub fn write_uniforms(
        &self,
        ctx: &Context,
        rays: &RayGen,
        (plan, settings): (&MarchPlan, &RenderSettings),
        slots: (&[BrickSlot], &[TextureSlot], SurfaceSlot),
        desc: &FrameDesc,
    ) {
        let params = RayUniforms::new(rays, plan, slots, settings, desc);
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        ctx.queue.write_buffer(
            &self.directions,
            0,
            bytemuck::cast_slice(&uniforms::directions(&plan.directions)),
        );
    }

    /// The bands a frame of `size` is cast in: each one's first row written
    /// to the bands buffer, and its workgroups.
    pub fn write_bands(&self, ctx: &Context, size: UVec2) -> Vec<[u32; 3]> {
        let rows = adapter_band_rows(ctx, size);
        let software = ctx.info.device_type == wgpu::DeviceType::Cpu;
        let first_rows: Vec<u32> = (0..size.y).step_by(rows as usize).collect();
        let bands: Vec<[u32; 3]> = first_rows
            .iter()
            .map(|first| {
                let height = rows.min(size.y - first);
                [size.x.div_ceil(WORKGROUP), height.div_ceil(WORKGROUP), 1]
            })
            .collect();
        let mut words = vec![0u32; first_rows.len() * (BAND_STRIDE / 4) as usize];
        for (band, (first, groups)) in first_rows.iter().zip(&bands).enumerate() {
            let at = band * (BAND_STRIDE / 4) as usize;
            words[at] = *first;
            words[at + 1] = match software {
                true => spread_stride(groups[0] * groups[1]),
                false => 1,
            };
        }
        ctx.queue
            .write_buffer(&self.bands, 0, bytemuck::cast_slice(&words));
        bands
    }

    /// Casts the frame the uniforms describe, band by band, watched;
    /// returns the pass's milliseconds.
    pub fn cast(
        &self,
        ctx: &Context,
        scene: &Scene,
        settings: &RenderSettings,
        size: UVec2,
        watch: Watch,
    ) -> Result<f64, RenderError> {
        let bands = self.write_bands(ctx, size);
        watch.expect(bands.len() as u64);
        let group = self.group()?;
        let pass = Pass {
            pipeline: self
                .pipelines
                .get(ctx, SceneKey::of(ctx, scene, settings)?)?,
            groups: &[group],
            band: Some(&self.band_group),
        };
        ctx.dispatch_bands(&pass, &bands, watch)
    }

    /// Copies the left (or only) eye's frame out of the target buffers,
    /// its hits (if `desc` asks for them) named as in `scene`.
    pub fn read_frame(
        &self,
        ctx: &Context,
        desc: &FrameDesc,
        scene: &Scene,
    ) -> Result<Frame, RenderError> {
        let target = self.target.as_ref().ok_or_else(unprepared)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&target.color, 0, &target.color_read, 0, None);
        if desc.depth {
            encoder.copy_buffer_to_buffer(&target.depth, 0, &target.depth_read, 0, None);
        }
        encoder.copy_buffer_to_buffer(&target.samples, 0, &target.samples_read, 0, None);
        ctx.queue.submit([encoder.finish()]);
        ctx.check()?;

        let color = ctx.read(&target.color_read, target.color_bytes())?;
        let depth = if desc.depth {
            Some(floats(
                &ctx.read(&target.depth_read, target.scalar_bytes())?,
            ))
        } else {
            None
        };
        let words = ctx.read(&target.samples_read, target.samples_read.size())?;
        let stride = 4 * target.pixel_words as usize;
        let samples = words
            .chunks_exact(stride)
            .map(|b| u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
            .sum();
        let hits = (desc.hits && target.pixel_words > 1).then(|| {
            let records: Vec<HitRecord> = words
                .chunks_exact(stride)
                .map(|b| bytemuck::pod_read_unaligned(&b[4..4 + size_of::<HitRecord>()]))
                .collect();
            hits::resolve(scene, &records)
        });
        ctx.check()?;
        Ok(Frame {
            size: desc.size,
            color: color_data(desc.color, color),
            depth,
            hits,
            samples,
        })
    }
}

/// Pixels per band of a frame cast in bands: 1920 x 1080 is 8 bands.
const BAND_PIXELS: u32 = 1 << 18;
/// Pixels per band on a software adapter (Mesa's lavapipe).
const SOFTWARE_BAND_PIXELS: u32 = 1 << 14;
/// The most bands a frame is cast in.
const MAX_BANDS: u32 = 1024;

/// The bands `write_bands` casts a frame of `size` in.
pub(super) fn band_count(ctx: &Context, size: UVec2) -> u64 {
    u64::from(size.y.div_ceil(adapter_band_rows(ctx, size)))
}

/// Rows per band of a frame of `size` on this adapter.
fn adapter_band_rows(ctx: &Context, size: UVec2) -> u32 {
    // A software adapter takes hundreds of times longer over a band:
    // smaller bands keep a discard as prompt there.
    let pixels = match ctx.info.device_type {
        wgpu::DeviceType::Cpu => SOFTWARE_BAND_PIXELS,
        _ => BAND_PIXELS,
    };
    band_rows(size, pixels)
}

/// A stride coprime to `n` near n / golden ratio: tile (i * stride) mod n
/// for workgroup i visits every tile once, and any run of consecutive
/// workgroups is spread evenly over the band (band.wgsl). 1 where the
/// product would not fit the shader's u32 arithmetic.
fn spread_stride(n: u32) -> u32 {
    if n <= 2 || n > 1 << 16 {
        return 1;
    }
    let gcd = |mut a: u32, mut b: u32| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let start = ((f64::from(n) * 0.618_034).round() as u32).max(1);
    (start..n).find(|&p| gcd(p, n) == 1).unwrap_or(1)
}

/// Rows per band of a frame of `size`: whole workgroups, about `pixels`,
/// and no more than MAX_BANDS bands.
fn band_rows(size: UVec2, pixels: u32) -> u32 {
    let by_pixels = (pixels / size.x.max(1)).max(1);
    let by_count = size.y.div_ceil(MAX_BANDS);
    by_pixels.max(by_count).next_multiple_of(WORKGROUP)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu::bindings::assert_declared;
    use crate::render::gpu::shaders::compose;

    #[test]
    fn the_spread_visits_every_tile_once_and_spreads_every_run() {
        for n in [1u32, 2, 3, 4, 32, 64, 96, 256, 1000, 4096, 65536] {
            let p = spread_stride(n);
            let mut seen = vec![false; n as usize];
            for i in 0..n {
                let tile = (i * p) % n;
                assert!(!seen[tile as usize], "n {n}, stride {p}: tile {tile} twice");
                seen[tile as usize] = true;
            }
            // The first half of the workgroups (one of two threads' runs)
            // reaches into every quarter of the band.
            if n >= 16 {
                for quarter in 0..4 {
                    let hit = (0..n / 2).any(|i| (i * p) % n * 4 / n == quarter);
                    assert!(hit, "n {n}, stride {p}: quarter {quarter} missed");
                }
            }
        }
        assert_eq!(spread_stride(1 << 17), 1);
    }

    #[test]
    fn bands_cover_the_frame_in_whole_workgroups() {
        for size in [
            UVec2::new(1, 1),
            UVec2::new(24, 40),
            UVec2::new(1920, 1080),
            UVec2::new(16384, 16384),
            UVec2::new(1, 100_000),
        ] {
            for pixels in [BAND_PIXELS, SOFTWARE_BAND_PIXELS] {
                let rows = band_rows(size, pixels);
                assert_eq!(rows % WORKGROUP, 0, "{size}");
                assert!(size.y.div_ceil(rows) <= MAX_BANDS, "{size}: {rows} rows");
            }
        }
        let hd = UVec2::new(1920, 1080);
        assert_eq!(hd.y.div_ceil(band_rows(hd, BAND_PIXELS)), 8);
        assert_eq!(hd.y.div_ceil(band_rows(hd, SOFTWARE_BAND_PIXELS)), 135);
    }

    #[test]
    fn the_raycast_shader_declares_its_tables() {
        for filterable in [false, true] {
            let groups = [&VolumeLayout::table(filterable), &BandLayout::table()];
            assert_declared(&compose("raycast", &groups).unwrap(), &groups);
        }
    }
}
