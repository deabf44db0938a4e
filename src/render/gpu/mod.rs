//! The wgpu ray caster: shaders/volume.wgsl + raycast.wgsl, one invocation per pixel,
//! and the re-projection stereo path (layers.rs). Device, pipelines and
//! buffers are made once; the volume and the table are uploaded when a
//! scene brings new ones and kept otherwise.

mod capture;
mod context;
mod iso;
mod layers;
pub(crate) mod resources;
mod shaders;
mod uniforms;
mod warp;

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use glam::UVec2;

pub use self::context::PassClock;

use self::context::{Context, Pass, BAND_STRIDE};
use self::resources::OutputBuffers;
use self::uniforms::{BrickSlot, Params, WORKGROUP};
use super::empty_space::{EmptySpace, SpaceCache};
use super::frame::{ColorData, ColorFormat, Frame, FrameDesc};
use super::march_plan::MarchPlan;
use super::settings::MAX_DIRECTIONS;
use super::{BackgroundImage, RenderError, RenderSettings, Sampling};
use crate::geometry::RayGen;
use crate::scene::{Scene, StructuredVolume, TransferFunction, MAX_VOLUMES};

/// How often data went to the GPU; lets tests (and curious users) check
/// that unchanged scenes are not uploaded again.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Uploads {
    pub volumes: u32,
    pub transfer_functions: u32,
}

pub struct GpuRenderer {
    ctx: Context,
    pipeline: Variants,
    /// The same march with hardware-filtered samples, where the adapter
    /// filters 32-bit floats.
    filtered: Option<Variants>,
    sampler: wgpu::Sampler,
    mip_sampler: wgpu::Sampler,
    /// Whether the volume textures carry mip chains: from the first frame
    /// with level of detail on (software Vulkan samples textures without
    /// them faster, so full detail does not pay for them before).
    mips: bool,
    /// Which table and step exponent each stepped table row holds.
    stepped: [Option<(Arc<TransferFunction>, f32)>; MAX_VOLUMES],
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    directions: wgpu::Buffer,
    /// Each band's first row, BAND_STRIDE bytes apart, and the group that
    /// binds one of them.
    bands: wgpu::Buffer,
    band_group: wgpu::BindGroup,
    band_layout: wgpu::BindGroupLayout,
    /// The scene's volumes on the GPU, in its order.
    volumes: Vec<(Arc<StructuredVolume>, wgpu::TextureView)>,
    /// Bound where a scene has fewer than MAX_VOLUMES volumes.
    no_volume: wgpu::TextureView,
    /// One row per volume slot; which transfer function each row holds.
    table: wgpu::Texture,
    table_view: wgpu::TextureView,
    tables: [Option<Arc<TransferFunction>>; MAX_VOLUMES],
    /// The background image bound now (`None`: the stand-in), and the
    /// stand-in bound when there is none.
    background: Option<(Arc<BackgroundImage>, wgpu::TextureView)>,
    no_background: wgpu::TextureView,
    target: Option<OutputBuffers>,
    bind_group: Option<wgpu::BindGroup>,
    uploads: Uploads,
    stereo: Option<layers::StereoGpu>,
    last_pass_ms: f64,
    /// Each placed volume's clear bricks under its table, which the bricks
    /// buffer holds.
    space_cache: SpaceCache,
    bricks: wgpu::Buffer,
    brick_slots: Vec<BrickSlot>,
    /// The warp passes, made on the first warp.
    warper: Option<warp::GpuWarp>,
    /// The capture pipelines and layer buffers, made on the first capture.
    capture: Option<capture::CaptureGpu>,
    /// The isosurface pipeline, made on the first cast.
    iso: Option<iso::IsoGpu>,
}

impl GpuRenderer {
    /// Opens the first Vulkan adapter (lavapipe where there is no GPU).
    pub fn new() -> Result<Self, RenderError> {
        let ctx = Context::new()?;
        let device = &ctx.device;
        // Filterable where the adapter filters 32-bit floats: then the
        // filtered pipeline reads the same textures through a sampler.
        let filterable = ctx.filterable;
        let texture = |dim| wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable },
            view_dimension: dim,
            multisampled: false,
        };
        let sampler_type = if filterable {
            wgpu::SamplerBindingType::Filtering
        } else {
            wgpu::SamplerBindingType::NonFiltering
        };
        let storage = |read_only| buffer_type(wgpu::BufferBindingType::Storage { read_only });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raycast"),
            entries: &[
                layout_entry(0, buffer_type(wgpu::BufferBindingType::Uniform)),
                layout_entry(1, texture(wgpu::TextureViewDimension::D3)),
                layout_entry(2, texture(wgpu::TextureViewDimension::D2)),
                layout_entry(3, storage(true)),
                layout_entry(4, storage(false)),
                layout_entry(5, storage(false)),
                layout_entry(6, storage(false)),
                layout_entry(7, texture(wgpu::TextureViewDimension::D2)),
                layout_entry(8, texture(wgpu::TextureViewDimension::D3)),
                layout_entry(9, texture(wgpu::TextureViewDimension::D3)),
                layout_entry(10, texture(wgpu::TextureViewDimension::D3)),
                layout_entry(11, texture(wgpu::TextureViewDimension::D3)),
                layout_entry(12, texture(wgpu::TextureViewDimension::D3)),
                layout_entry(13, texture(wgpu::TextureViewDimension::D3)),
                layout_entry(14, texture(wgpu::TextureViewDimension::D3)),
                layout_entry(15, storage(true)),
                layout_entry(16, wgpu::BindingType::Sampler(sampler_type)),
                layout_entry(17, wgpu::BindingType::Sampler(sampler_type)),
            ],
        });
        let band_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("band"),
            entries: &[layout_entry(
                0,
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: true,
                    min_binding_size: wgpu::BufferSize::new(16),
                },
            )],
        });
        let source = shaders::raycast();
        let layouts = [&layout, &band_layout];
        // One pipeline per sampling mode, each for one volume or several.
        let variant = |filtered: bool, one: bool| {
            let flag = |b: bool| if b { 1.0 } else { 0.0 };
            compute_pipeline_with(
                device,
                "raycast",
                &source,
                &layouts,
                "main",
                &[("FILTERED", flag(filtered)), ("ONE_VOLUME", flag(one))],
            )
        };
        let pipeline = Variants {
            one: variant(false, true),
            several: variant(false, false),
        };
        let filtered = filterable.then(|| Variants {
            one: variant(true, true),
            several: variant(true, false),
        });
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
            size_of::<Params>() as u64,
            wgpu::BufferUsages::UNIFORM,
        );
        let directions = uniform(
            "directions",
            16 * u64::from(MAX_DIRECTIONS),
            wgpu::BufferUsages::STORAGE,
        );
        let no_background = resources::upload_background(&ctx, None);
        let no_volume = resources::stand_in_volume(&ctx);
        let bands = uniform(
            "bands",
            u64::from(MAX_BANDS * BAND_STRIDE),
            wgpu::BufferUsages::UNIFORM,
        );
        let band_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("band"),
            layout: &band_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &bands,
                    offset: 0,
                    size: wgpu::BufferSize::new(16),
                }),
            }],
        });
        let table = resources::table_texture(&ctx);
        let table_view = table.create_view(&Default::default());
        let (bricks, _) = resources::bricks_buffer(&ctx, &[]);
        ctx.check()?;
        Ok(Self {
            ctx,
            pipeline,
            filtered,
            sampler,
            mip_sampler,
            mips: false,
            stepped: Default::default(),
            layout,
            params,
            directions,
            bands,
            band_group,
            band_layout,
            volumes: Vec::new(),
            no_volume,
            table,
            table_view,
            tables: Default::default(),
            background: None,
            no_background,
            target: None,
            bind_group: None,
            uploads: Uploads::default(),
            stereo: None,
            last_pass_ms: 0.0,
            space_cache: SpaceCache::default(),
            bricks,
            brick_slots: Vec::new(),
            warper: None,
            capture: None,
            iso: None,
        })
    }

    /// The adapter `new` would open, without opening it.
    pub fn probe() -> Result<wgpu::AdapterInfo, RenderError> {
        Context::probe()
    }

    /// GPU time of the last frame's ray casting pass (no upload or
    /// read-back), in milliseconds, by [`GpuRenderer::pass_clock`].
    /// `source` shown from `target` (an image of `size`) by the GPU warp
    /// passes, which the CPU's [`crate::render::warp::warp`] is the
    /// reference for; with the passes' milliseconds.
    pub fn warp(
        &mut self,
        source: &crate::render::warp::Source,
        target: &RayGen,
        size: UVec2,
        settings: &crate::render::warp::WarpSettings,
    ) -> Result<(crate::render::warp::Warped, f64), RenderError> {
        let ctx = &self.ctx;
        let warper = self.warper.get_or_insert_with(|| warp::GpuWarp::new(ctx));
        let result = warper.warp(ctx, source, target, size, settings);
        ctx.check()?;
        result
    }

    pub fn last_pass_ms(&self) -> f64 {
        self.last_pass_ms
    }

    /// Whether pass times are GPU timestamps or the host's clock.
    pub fn pass_clock(&self) -> PassClock {
        self.ctx.pass_clock()
    }

    pub fn adapter(&self) -> &wgpu::AdapterInfo {
        &self.ctx.info
    }
    pub fn limits(&self) -> &wgpu::Limits {
        &self.ctx.limits
    }
    pub fn uploads(&self) -> Uploads {
        self.uploads
    }

    /// Fails, before touching the GPU, if the scene or frame exceeds what
    /// this adapter allows.
    pub fn check_limits(&self, scene: &Scene, desc: &FrameDesc) -> Result<(), RenderError> {
        let limits = &self.ctx.limits;
        let max = limits.max_texture_dimension_3d;
        for placed in scene.volumes() {
            let dims = placed.volume.dims();
            if dims.max_element() > max {
                return Err(RenderError::VolumeTooLarge {
                    dims: [dims.x, dims.y, dims.z],
                    max,
                    adapter: self.ctx.info.name.clone(),
                });
            }
        }
        let pixels = u64::from(desc.size.x) * u64::from(desc.size.y);
        let bytes = pixels * desc.color.bytes_per_pixel();
        let max_bytes = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let groups = desc.size.max_element().div_ceil(WORKGROUP);
        let reason = if bytes > max_bytes {
            Some(format!(
                "its {bytes} bytes of color exceed the largest storage buffer ({max_bytes} bytes)"
            ))
        } else if groups > limits.max_compute_workgroups_per_dimension {
            Some(format!(
                "{groups} workgroups per side exceed the limit of {}",
                limits.max_compute_workgroups_per_dimension
            ))
        } else {
            None
        };
        if let Some(reason) = reason {
            return Err(RenderError::FrameTooLarge {
                size: [desc.size.x, desc.size.y],
                reason,
                adapter: self.ctx.info.name.clone(),
            });
        }
        Ok(())
    }

    pub fn render(
        &mut self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
    ) -> Result<Frame, RenderError> {
        self.render_until(scene, rays, settings, desc, &AtomicBool::new(false))
    }

    /// `render`, cast in bands of rows (about BAND_PIXELS each), each its
    /// own submission: once `stop` is set no further band starts, and
    /// `RenderError::Stopped` is returned.
    pub fn render_until(
        &mut self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
        stop: &AtomicBool,
    ) -> Result<Frame, RenderError> {
        self.begin(scene, rays, settings, desc)?;
        let bands = self.write_bands(desc.size);
        let bind_group = self.bind_group.as_ref().ok_or_else(unprepared)?;
        let pipeline = self.variant(&self.pipeline, &self.filtered, scene, settings)?;
        let pass = Pass {
            pipeline,
            groups: &[bind_group],
            band: Some(&self.band_group),
        };
        self.last_pass_ms = self.ctx.dispatch_bands(&pass, &bands, stop)?;
        self.read_frame(desc)
    }

    /// The bands a frame of `size` is cast in: each one's first row written
    /// to the bands buffer, and its workgroups.
    fn write_bands(&self, size: UVec2) -> Vec<[u32; 3]> {
        let rows = band_rows(size);
        let first_rows: Vec<u32> = (0..size.y).step_by(rows as usize).collect();
        let mut words = vec![0u32; first_rows.len() * (BAND_STRIDE / 4) as usize];
        for (band, first) in first_rows.iter().enumerate() {
            words[band * (BAND_STRIDE / 4) as usize] = *first;
        }
        self.ctx
            .queue
            .write_buffer(&self.bands, 0, bytemuck::cast_slice(&words));
        first_rows
            .iter()
            .map(|first| {
                let height = rows.min(size.y - first);
                [size.x.div_ceil(WORKGROUP), height.div_ceil(WORKGROUP), 1]
            })
            .collect()
    }

    /// Of a shader's pipelines (`exact`, and `filtered` where the adapter
    /// filters), the one for the settings' sampling and the scene's count
    /// of volumes.
    fn variant<'a>(
        &self,
        exact: &'a Variants,
        filtered: &'a Option<Variants>,
        scene: &Scene,
        settings: &RenderSettings,
    ) -> Result<&'a wgpu::ComputePipeline, RenderError> {
        let variants = match settings.sampling {
            Sampling::Exact => exact,
            Sampling::Filtered => filtered.as_ref().ok_or_else(|| self.no_filtering())?,
        };
        Ok(if scene.volumes().len() == 1 {
            &variants.one
        } else {
            &variants.several
        })
    }

    /// Checks the frame against the adapter, uploads what changed and
    /// writes the uniforms for ray casting `rays`.
    fn begin(
        &mut self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
    ) -> Result<(), RenderError> {
        desc.validate()?;
        let plan = MarchPlan::new(scene, rays, settings)?;
        self.check_limits(scene, desc)?;
        if plan.skipping {
            self.find_clear_bricks(scene, &plan)?;
        }
        let filtered = settings.sampling == Sampling::Filtered;
        if filtered && self.filtered.is_none() {
            return Err(self.no_filtering());
        }
        if filtered && settings.level_of_detail > 0.0 && !self.mips {
            // Upload the volumes again, with their mip chains.
            self.mips = true;
            self.volumes.clear();
            self.bind_group = None;
        }
        self.prepare(
            scene,
            desc.size,
            desc.color,
            settings.background_image.as_ref(),
        );
        if filtered {
            self.write_stepped_tables(scene, &plan);
        }
        let queue = &self.ctx.queue;
        let bricks: &[BrickSlot] = if plan.skipping {
            &self.brick_slots
        } else {
            &[]
        };
        let params = Params::new(rays, &plan, bricks, desc.size, desc.color);
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        queue.write_buffer(
            &self.directions,
            0,
            bytemuck::cast_slice(&uniforms::directions(&plan.directions)),
        );
        Ok(())
    }

    /// Copies the left (or only) eye's frame out of the target buffers.
    fn read_frame(&self, desc: &FrameDesc) -> Result<Frame, RenderError> {
        let ctx = &self.ctx;
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
        let samples = ctx
            .read(&target.samples_read, target.scalar_bytes())?
            .chunks_exact(4)
            .map(|b| u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
            .sum();
        ctx.check()?;
        Ok(Frame {
            size: desc.size,
            color: color_data(desc.color, color),
            depth,
            samples,
        })
    }

    /// Uploads the scene's volume and transfer function now, if they are
    /// not on the GPU yet, and waits for the copy: lets callers time
    /// uploads apart from frames.
    pub fn upload(&mut self, scene: &Scene) -> Result<(), RenderError> {
        self.check_limits(scene, &FrameDesc::new(UVec2::ONE))?;
        self.upload_scene(scene);
        self.ctx.queue.submit([]);
        self.ctx.wait()?;
        self.ctx.check()
    }

    /// Uploads whatever of the scene is not on the GPU; true if the
    /// volumes bound changed (tables are rows of one texture, rewritten in
    /// place).
    fn upload_scene(&mut self, scene: &Scene) -> bool {
        let mut volumes = Vec::with_capacity(scene.volumes().len());
        for placed in scene.volumes() {
            // A grid placed twice is one texture.
            let kept = volumes
                .iter()
                .chain(&self.volumes)
                .find(|(v, _)| Arc::ptr_eq(v, &placed.volume))
                .map(|(_, view)| view.clone());
            let view = kept.unwrap_or_else(|| {
                self.uploads.volumes += 1;
                resources::upload_volume(&self.ctx, &placed.volume, self.mips)
            });
            volumes.push((Arc::clone(&placed.volume), view));
        }
        let changed = volumes.len() != self.volumes.len()
            || volumes
                .iter()
                .zip(&self.volumes)
                .any(|((a, _), (b, _))| !Arc::ptr_eq(a, b));
        self.volumes = volumes;
        for (row, placed) in scene.volumes().iter().enumerate() {
            let tf = &placed.transfer_function;
            if !matches!(&self.tables[row], Some(t) if Arc::ptr_eq(t, tf)) {
                resources::write_table(&self.ctx, &self.table, row as u32, tf);
                self.tables[row] = Some(Arc::clone(tf));
                self.uploads.transfer_functions += 1;
            }
        }
        if changed {
            self.bind_group = None;
        }
        changed
    }

    /// Whether this adapter runs filtered sampling.
    pub fn filters(&self) -> bool {
        self.filtered.is_some()
    }

    fn no_filtering(&self) -> RenderError {
        RenderError::Settings(format!(
            "filtered GPU sampling needs 32-bit float textures to filter, which {} does not offer; use exact sampling",
            self.ctx.info.name
        ))
    }

    /// The tables with opacities corrected for this plan's primary step,
    /// rewritten where the table or the step changed.
    fn write_stepped_tables(&mut self, scene: &Scene, plan: &MarchPlan) {
        for (row, (placed, vplan)) in scene.volumes().iter().zip(&plan.volumes).enumerate() {
            let tf = &placed.transfer_function;
            let exponent = plan.step * vplan.inv_unit_distance;
            let current =
                matches!(&self.stepped[row], Some((t, e)) if Arc::ptr_eq(t, tf) && *e == exponent);
            if !current {
                resources::write_stepped_table(&self.ctx, &self.table, row as u32, tf, exponent);
                self.stepped[row] = Some((Arc::clone(tf), exponent));
            }
        }
    }

    /// Makes the clear-brick distances of the scene's volumes under their
    /// tables, where they are new, and the buffer that holds them; a new
    /// buffer means a new bind group.
    fn find_clear_bricks(&mut self, scene: &Scene, plan: &MarchPlan) -> Result<(), RenderError> {
        let (spaces, changed) = self.space_cache.update(scene, plan)?;
        if changed {
            let list: Vec<&EmptySpace> = spaces.iter().map(Arc::as_ref).collect();
            (self.bricks, self.brick_slots) = resources::bricks_buffer(&self.ctx, &list);
            self.bind_group = None;
        }
        Ok(())
    }

    /// Uploads what changed and rebuilds the bind group if anything did.
    fn prepare(
        &mut self,
        scene: &Scene,
        size: UVec2,
        format: ColorFormat,
        background: Option<&Arc<BackgroundImage>>,
    ) {
        let mut changed = self.bind_group.is_none();
        changed |= self.upload_scene(scene);
        let same_background = match (&self.background, background) {
            (None, None) => true,
            (Some((a, _)), Some(b)) => Arc::ptr_eq(a, b),
            _ => false,
        };
        if !same_background {
            self.background = background.map(|b| {
                (
                    Arc::clone(b),
                    resources::upload_background(&self.ctx, Some(b)),
                )
            });
            changed = true;
        }
        if !matches!(&self.target, Some(t) if t.size == size && t.format == format) {
            self.target = Some(OutputBuffers::new(&self.ctx, size, format));
            changed = true;
        }
        if changed {
            let volume = |i: usize| {
                wgpu::BindingResource::TextureView(
                    self.volumes.get(i).map_or(&self.no_volume, |(_, v)| v),
                )
            };
            let target = self.target.as_ref().expect("made above");
            fn buffer(b: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
                b.as_entire_binding()
            }
            // In binding order, as shaders/volume.wgsl declares them.
            let resources = [
                buffer(&self.params),
                volume(0),
                wgpu::BindingResource::TextureView(&self.table_view),
                buffer(&self.directions),
                buffer(&target.color),
                buffer(&target.depth),
                buffer(&target.samples),
                wgpu::BindingResource::TextureView(
                    self.background
                        .as_ref()
                        .map_or(&self.no_background, |(_, v)| v),
                ),
                volume(1),
                volume(2),
                volume(3),
                volume(4),
                volume(5),
                volume(6),
                volume(7),
                buffer(&self.bricks),
                wgpu::BindingResource::Sampler(&self.sampler),
                wgpu::BindingResource::Sampler(&self.mip_sampler),
            ];
            let group = bind_group(&self.ctx.device, "raycast", &self.layout, resources);
            self.bind_group = Some(group);
        }
    }
}

/// A ray casting pipeline for scenes of one volume and of several.
struct Variants {
    one: wgpu::ComputePipeline,
    several: wgpu::ComputePipeline,
}

/// Pixels per band of a frame cast in bands: 1920 x 1080 is 8 bands.
const BAND_PIXELS: u32 = 1 << 18;
/// The most bands a frame is cast in.
const MAX_BANDS: u32 = 64;

/// Rows per band of a frame of `size`: whole workgroups, about
/// BAND_PIXELS, and no more than MAX_BANDS bands.
fn band_rows(size: UVec2) -> u32 {
    let by_pixels = (BAND_PIXELS / size.x.max(1)).max(1);
    let by_count = size.y.div_ceil(MAX_BANDS);
    by_pixels.max(by_count).next_multiple_of(WORKGROUP)
}

/// Builds a compute pipeline from WGSL source with explicit layouts.
fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    layouts: &[&wgpu::BindGroupLayout],
    entry: &str,
) -> wgpu::ComputePipeline {
    compute_pipeline_with(device, label, source, layouts, entry, &[])
}

/// `compute_pipeline` with values for the shader's override constants.
fn compute_pipeline_with(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    layouts: &[&wgpu::BindGroupLayout],
    entry: &str,
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(|l| Some(*l)).collect();
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            ..Default::default()
        },
        cache: None,
    })
}

/// A compute-only bind group layout entry.
fn layout_entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty,
        count: None,
    }
}

fn buffer_type(ty: wgpu::BufferBindingType) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

/// A bind group whose resources are bound at 0, 1, 2, ... in order.
fn bind_group<const N: usize>(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: [wgpu::BindingResource; N],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = resources
        .into_iter()
        .enumerate()
        .map(|(binding, resource)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource,
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

fn unprepared() -> RenderError {
    RenderError::Gpu("internal: render target used before it was made".into())
}

fn color_data(format: ColorFormat, bytes: Vec<u8>) -> ColorData {
    match format {
        ColorFormat::Rgba8 => ColorData::Rgba8(bytes),
        ColorFormat::Srgba8 => ColorData::Srgba8(bytes),
        ColorFormat::Rgba32F => ColorData::Rgba32F(floats(&bytes)),
    }
}

fn floats(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_the_frame_in_whole_workgroups() {
        for size in [
            UVec2::new(1, 1),
            UVec2::new(24, 40),
            UVec2::new(1920, 1080),
            UVec2::new(16384, 16384),
            UVec2::new(1, 100_000),
        ] {
            let rows = band_rows(size);
            assert_eq!(rows % WORKGROUP, 0, "{size}");
            assert!(size.y.div_ceil(rows) <= MAX_BANDS, "{size}: {rows} rows");
        }
        assert_eq!(
            UVec2::new(1920, 1080)
                .y
                .div_ceil(band_rows(UVec2::new(1920, 1080))),
            8
        );
    }
}
