//! The wgpu renderer: one shared context (context.rs), the scene as
//! uploaded (scene.rs), and one pass per job, each owning its pipelines,
//! binding tables and bind groups: ray casting (raycast.rs), re-projection
//! stereo and its compositing (layers.rs), warps (warp.rs), the capture
//! warps start from (capture.rs) and isosurfaces (iso.rs). The ray caster
//! is made with the renderer, the other passes on their first use.
//! Shaders are composed from the WGSL modules in shaders/ (shaders.rs,
//! modules.rs); each pass's bindings are declared once, in its table
//! (bindings.rs).

mod amr;
mod bindings;
mod capture;
mod context;
mod iso;
mod layers;
mod mesh;
mod modules;
mod nanovdb;
mod paging;
mod raycast;
mod resources;
mod scene;
mod shaders;
mod uniforms;
mod variant;
mod volume_texture;
mod warp;

use std::sync::atomic::AtomicBool;

use glam::{UVec2, Vec4};

pub use self::context::PassClock;
pub use self::paging::{StreamWait, Streaming};
pub use self::scene::Uploads;

use self::capture::{layer_bytes, CapturePass};
use self::context::{unprepared, Context};
use self::iso::IsoPass;
use self::layers::{no_layers, LayersPass};
use self::raycast::RaycastPass;
use self::scene::GpuScene;
use self::variant::no_filtering;
use self::warp::WarpPass;
use super::frame::{ColorData, Frame, FrameDesc};
use super::march_plan::MarchPlan;
use super::stereo::{Reprojection, StereoFrames};
use super::warp::{check_layers, surface_layer_depth, Source};
use super::{ColorFormat, Render, RenderError, RenderSettings, Sampling, Watch};
use crate::geometry::RayGen;
use crate::render::iso::{IsoSettings, MultiViewMethod, Panel};
use crate::scene::{PlacedVolume, Scene};

pub struct GpuRenderer {
    ctx: Context,
    scene: GpuScene,
    raycast: RaycastPass,
    /// Re-projection stereo, made on the first re-projected frame and made
    /// again when the layer format changes.
    stereo: Option<LayersPass>,
    /// The warp passes, made on the first warp.
    warper: Option<WarpPass>,
    /// The capture pipelines and layer buffers, made on the first capture.
    capture: Option<CapturePass>,
    /// The isosurface pipelines, made on the first cast.
    iso: Option<IsoPass>,
    last_pass_ms: f64,
    /// How long a frame waits for the bricks of paged volumes.
    stream_wait: StreamWait,
    /// How much of what the last frame selected was resident.
    streaming: Streaming,
}

impl GpuRenderer {
    /// Opens the first Vulkan adapter (lavapipe where there is no GPU).
    pub fn new() -> Result<Self, RenderError> {
        let ctx = Context::new()?;
        let raycast = RaycastPass::new(&ctx)?;
        let scene = GpuScene::new(&ctx);
        ctx.check()?;
        Ok(Self {
            ctx,
            scene,
            raycast,
            stereo: None,
            warper: None,
            capture: None,
            iso: None,
            last_pass_ms: 0.0,
            stream_wait: StreamWait::Complete,
            streaming: Streaming::default(),
        })
    }

    /// The adapter `new` would open, without opening it.
    pub fn probe() -> Result<wgpu::AdapterInfo, RenderError> {
        Context::probe()
    }

    /// `source` shown from `target` (an image of `size`) by the GPU warp
    /// passes, which the CPU's [`crate::render::warp::warp`] is the
    /// reference for; with the passes' milliseconds.
    pub fn warp(
        &mut self,
        source: &Source,
        target: &RayGen,
        size: UVec2,
        settings: &crate::render::warp::WarpSettings,
    ) -> Result<(crate::render::warp::Warped, f64), RenderError> {
        let ctx = &self.ctx;
        let warper = match &mut self.warper {
            Some(w) => w,
            None => self.warper.insert(WarpPass::new(ctx)?),
        };
        let result = warper.warp(ctx, source, target, size, settings);
        ctx.check()?;
        result
    }

    /// GPU time of the last frame's ray casting pass (no upload or
    /// read-back), in milliseconds, by [`GpuRenderer::pass_clock`].
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
        self.scene.uploads()
    }

    /// Every volume paged, in bricks of `texels` a side, from now on
    /// (None: only those longer than the adapter's 3D texture limit or
    /// past the memory budget, in bricks of 64): lets tests and
    /// benchmarks page volumes small enough to compare with a whole
    /// texture. Volumes on the GPU are uploaded again.
    pub fn brick_every_volume(&mut self, texels: Option<u32>) {
        self.ctx.brick_texels = texels;
        self.scene.forget_volumes();
    }

    /// At most `bytes` of volume textures from now on (None: as many as
    /// the adapter allocates): the volumes of a scene past it are paged,
    /// each pool its share of the budget; one too small for a single
    /// brick is refused before anything is allocated, and `Backend::Auto`
    /// renders it on the CPU.
    pub fn set_memory_budget(&mut self, bytes: Option<u64>) {
        self.ctx.memory_budget = bytes;
        self.ctx.driver_budget = None;
    }

    /// How long a frame waits for the bricks of paged volumes from now on:
    /// until all it selected are resident (`Complete`, the default), or
    /// at most a budget, after which it renders what is resident (coarser
    /// levels where bricks are missing) and later frames refine.
    pub fn set_stream_wait(&mut self, wait: StreamWait) {
        self.stream_wait = wait;
    }

    /// How much of what the last frame selected of its paged volumes was
    /// resident ([`Streaming::progress`]).
    pub fn streaming(&self) -> Streaming {
        self.streaming
    }

    /// Whether 16-bit volumes sit in 16-bit textures here (else in
    /// 32-bit floats).
    pub fn has_16bit_textures(&self) -> bool {
        self.ctx.norm16
    }

    /// Bytes the current scene's volume textures hold on the GPU.
    pub fn volume_bytes(&self) -> u64 {
        self.scene.volume_bytes()
    }

    /// The memory budget volumes are laid out for: the one set, or what
    /// the driver was found to allocate, whichever is smaller.
    pub fn memory_budget(&self) -> Option<u64> {
        self.ctx.budget()
    }

    /// Bytes the current scene's paged volumes keep in host memory beside
    /// their voxels: their coarser levels, once made.
    pub fn host_volume_bytes(&self) -> u64 {
        self.scene.host_volume_bytes()
    }

    /// `placed` as the scene an isosurface cast uploads, refused before
    /// touching the GPU where its field does not fit one texture (GPU
    /// isosurfaces read no bricks) or the memory budget.
    pub fn check_iso(&self, placed: &PlacedVolume) -> Result<Scene, RenderError> {
        let scene = Scene::placed(vec![placed.clone()])
            .map_err(|e| RenderError::Settings(e.to_string()))?;
        let dims = placed.volume.dims();
        let max = self.ctx.limits.max_texture_dimension_3d;
        if dims.max_element() > max {
            return Err(RenderError::VolumeTooLarge {
                dims: dims.to_array(),
                max,
                adapter: self.ctx.info.name.clone(),
            });
        }
        if self.ctx.brick_texels.is_some() {
            return Err(RenderError::Settings(
                "isosurfaces on the GPU read a volume from one texture, and this renderer was told to page every volume".into(),
            ));
        }
        let layout = paging::layouts(&self.ctx, &scene)?;
        if let Some(budget) = self.ctx.budget() {
            let bytes: u64 = layout.iter().map(|l| l.bytes()).sum();
            let whole = layout
                .iter()
                .all(|l| matches!(l, paging::Layout::Whole { .. }));
            if !whole {
                let bytes = dims.as_u64vec3().element_product().max(bytes);
                return Err(RenderError::OutOfMemory {
                    bytes,
                    what: format!(
                        "the isosurface's volume texture, past the GPU memory budget of {budget} bytes (isosurfaces read no paged volumes)"
                    ),
                });
            }
        }
        Ok(scene)
    }

    /// Fails, before touching the GPU, if the scene or frame exceeds what
    /// this adapter allows.
    pub fn check_limits(&self, scene: &Scene, desc: &FrameDesc) -> Result<(), RenderError> {
        paging::layouts(&self.ctx, scene)?;
        self.ctx.check_frame(desc)
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
        let ctx = &self.ctx;
        paging::layouts(ctx, scene)?;
        ctx.check_frame(desc)?;
        if plan.skipping {
            self.scene.find_clear_bricks(ctx, scene, &plan)?;
        }
        let filtered = settings.sampling == Sampling::Filtered;
        if filtered && !self.raycast.filters() {
            return Err(no_filtering(ctx));
        }
        if filtered && settings.level_of_detail > 0.0 {
            self.scene.use_mips();
        }
        self.upload_within_the_driver(scene)?;
        let ctx = &self.ctx;
        self.streaming = self.scene.stream(
            ctx,
            scene,
            &plan,
            rays,
            (settings.sampling, desc),
            self.stream_wait,
        )?;
        self.scene.upload_surfaces(ctx, scene)?;
        self.scene
            .set_background(ctx, settings.background_image.as_ref());
        self.raycast.bind(ctx, &self.scene, desc);
        if filtered {
            self.scene.write_stepped_tables(ctx, scene, &plan);
        }
        let textures = self.scene.texture_slots();
        let slots = (
            self.scene.brick_slots(plan.skipping),
            &textures[..],
            self.scene.surface_slot(),
        );
        self.raycast
            .write_uniforms(ctx, rays, (&plan, settings), slots, desc);
        Ok(())
    }

    /// Uploads the scene's volume and transfer function now, if they are
    /// not on the GPU yet, and waits for the copy: lets callers time
    /// uploads apart from frames.
    pub fn upload(&mut self, scene: &Scene) -> Result<(), RenderError> {
        self.check_limits(scene, &FrameDesc::new(UVec2::ONE))?;
        self.upload_within_the_driver(scene)?;
        self.ctx.queue.submit([]);
        self.ctx.wait()?;
        self.ctx.check()
    }

    /// Uploads the scene; where the driver refuses a texture or pool for
    /// lack of memory (past the limits checked before), lays the scene
    /// out again for half the bytes it asked for, paging its volumes,
    /// until the driver allocates it or a pool would hold no brick.
    fn upload_within_the_driver(&mut self, scene: &Scene) -> Result<(), RenderError> {
        loop {
            let asked: u64 = paging::layouts(&self.ctx, scene)?
                .iter()
                .map(paging::Layout::bytes)
                .sum();
            match self.scene.upload(&self.ctx, scene) {
                Err(RenderError::OutOfMemory { .. }) if asked > 1 => {
                    self.ctx.driver_budget = Some(asked / 2);
                }
                other => return other,
            }
        }
    }

    /// Whether this adapter runs filtered sampling.
    pub fn filters(&self) -> bool {
        self.raycast.filters()
    }

    /// Both eyes from one ray casting pass: the left eye from `left`'s
    /// rays, the right eye re-projected from them as `reprojection` plans,
    /// with a depth channel if `desc` has one. The frame size is the
    /// plan's.
    pub fn render_reprojected(
        &mut self,
        scene: &Scene,
        left: &RayGen,
        reprojection: &Reprojection,
        settings: &RenderSettings,
        desc: &FrameDesc,
    ) -> Result<StereoFrames, RenderError> {
        let never = AtomicBool::new(false);
        self.render_reprojected_until(scene, left, reprojection, settings, desc, &never)
    }

    /// `render_reprojected`, its march cast in bands of rows: once the
    /// watch's stop flag is set no further band starts, and
    /// `RenderError::Stopped` is returned. Counts the march's bands and
    /// one unit for the compositing.
    pub fn render_reprojected_until<'w>(
        &mut self,
        scene: &Scene,
        left: &RayGen,
        reprojection: &Reprojection,
        settings: &RenderSettings,
        desc: &FrameDesc,
        watch: impl Into<Watch<'w>>,
    ) -> Result<StereoFrames, RenderError> {
        let watch = watch.into();
        desc.validate()?;
        if desc.size != reprojection.size {
            return Err(RenderError::Settings(format!(
                "the frame is {}x{} but the re-projection was planned for {}x{}",
                desc.size.x, desc.size.y, reprojection.size.x, reprojection.size.y
            )));
        }
        LayersPass::check(&self.ctx, reprojection)?;
        if settings.background_image.is_some() {
            return Err(RenderError::Settings(
                "re-projection composites over a flat background only; render background images in two passes".into(),
            ));
        }
        self.begin(scene, left, settings, desc)?;
        let ctx = &self.ctx;
        let stereo = match &mut self.stereo {
            Some(s) if s.format() == reprojection.format => s,
            _ => self
                .stereo
                .insert(LayersPass::new(ctx, &self.raycast, reprojection.format)?),
        };
        let (right, times) = stereo.render(
            (ctx, &self.raycast),
            scene,
            reprojection,
            settings,
            desc,
            watch,
        )?;
        self.last_pass_ms = times.left_ms;
        let left = self.raycast.read_frame(ctx, desc, scene)?;
        Ok(StereoFrames { left, right, times })
    }

    /// Milliseconds a full clear of the last frame's layers takes: the
    /// cost the span scheme avoids, for the benchmark to report.
    pub fn time_layer_clear(&mut self) -> Result<f64, RenderError> {
        let stereo = self.stereo.as_ref().ok_or_else(no_layers)?;
        stereo.time_clear(&self.ctx, &self.raycast)
    }

    /// The last re-projected right eye composited again reading every
    /// left ray of the bounding depth range, and its milliseconds: what
    /// the compositing's block summary spares, to measure it and to check
    /// it changes no pixel.
    pub fn composite_every_offset(&mut self) -> Result<(Frame, f64), RenderError> {
        let stereo = self.stereo.as_mut().ok_or_else(no_layers)?;
        stereo.composite_every_offset(&self.ctx, &self.raycast)
    }

    /// `rays` cast for an image of `size` keeping `layers` layers a pixel
    /// (0: none), the background left out: what
    /// [`crate::render::CpuRenderer::capture`] makes, from the GPU. Returns
    /// the source and the pass's milliseconds (GPU timestamps where the
    /// adapter has them). Counts bands.
    pub fn capture<'w>(
        &mut self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        size: UVec2,
        layers: usize,
        watch: impl Into<Watch<'w>>,
    ) -> Result<(Source, f64), RenderError> {
        let watch = watch.into();
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
        let bytes = layer_bytes(size, layers);
        if bytes > self.ctx.limits.max_storage_buffer_binding_size {
            return Err(RenderError::FrameTooLarge {
                size: size.to_array(),
                reason: format!(
                    "its {layers} layers a pixel take {bytes} bytes, more than one buffer holds"
                ),
                adapter: self.ctx.info.name.clone(),
            });
        }
        let ctx = &self.ctx;
        let capture = match &mut self.capture {
            Some(c) => c,
            None => self.capture.insert(CapturePass::new(ctx, &self.raycast)?),
        };
        let (frame, kept, ms) = capture.capture(
            ctx,
            &self.raycast,
            scene,
            &settings,
            &desc,
            (layers, surface_layer_depth(scene.bounds())),
            bytes,
            watch,
        )?;
        self.last_pass_ms = ms;
        let (ColorData::Rgba32F(c), Some(depth)) = (frame.color, frame.depth) else {
            return Err(unprepared());
        };
        let color = c.chunks_exact(4).map(Vec4::from_slice).collect();
        Ok((
            Source::new(size, *rays, color, depth, kept, layers, frame.samples),
            ms,
        ))
    }

    /// `placed`'s isosurface seen through `rays`, as
    /// [`crate::render::iso::cast`] renders it, on the GPU, in bands of
    /// rows (counted): once the stop flag is set no further band starts,
    /// and `RenderError::Stopped` is returned.
    pub fn cast_iso<'w>(
        &mut self,
        placed: &PlacedVolume,
        rays: &RayGen,
        desc: &FrameDesc,
        settings: &IsoSettings,
        watch: impl Into<Watch<'w>>,
    ) -> Result<Frame, RenderError> {
        let watch = watch.into();
        self.iso_ready(placed, desc, settings)?;
        let volume = self.scene.first_volume().ok_or_else(unprepared)?;
        let iso = self.iso.as_mut().ok_or_else(unprepared)?;
        let (frame, ms) = iso.cast(
            &self.ctx,
            volume,
            placed,
            rays,
            desc,
            settings,
            None,
            (&self.raycast, watch),
        )?;
        self.last_pass_ms = ms;
        Ok(frame)
    }

    /// A multi-view panel's image, every subpixel from its own view, as
    /// [`crate::render::iso::render_display`] makes it: one ray a subpixel
    /// (`PerSubpixel`) or the geometric and spectral passes, in bands of
    /// rows (every pass's counted) until the stop flag is set. The naive
    /// way is the CPU's (or `cast_iso` per view).
    pub fn cast_display<'w>(
        &mut self,
        placed: &PlacedVolume,
        panel: &Panel,
        settings: &IsoSettings,
        method: MultiViewMethod,
        watch: impl Into<Watch<'w>>,
    ) -> Result<Frame, RenderError> {
        let watch = watch.into();
        if method == MultiViewMethod::Naive {
            return Err(RenderError::Settings(
                "the GPU makes a panel's image per subpixel or by passes; naive is cast_iso per view".into(),
            ));
        }
        let views = panel.views.len();
        if views == 0 || views > 256 {
            return Err(RenderError::Settings(format!(
                "a panel on the GPU has 1 to 256 views, not {views}"
            )));
        }
        let desc = FrameDesc::new(panel.size).with_color(panel.color);
        desc.validate()?;
        let v = |x: glam::Vec3| x.extend(0.0).to_array();
        let rays: Vec<[f32; 4]> = panel
            .views
            .iter()
            .flat_map(|r| {
                [
                    v(r.origin),
                    v(r.origin_dx),
                    v(r.origin_dy),
                    v(r.direction),
                    v(r.direction_dx),
                    v(r.direction_dy),
                    r.eye.map_or([0.0; 4], |e| e.extend(1.0).to_array()),
                ]
            })
            .collect();
        // Each pixel's three views, a byte each (at most 256 views).
        let packed: Vec<u32> = panel
            .checked_table()?
            .iter()
            .map(|v| v[0] | v[1] << 8 | v[2] << 16)
            .collect();
        self.iso_ready(placed, &desc, settings)?;
        let volume = self.scene.first_volume().ok_or_else(unprepared)?;
        let iso = self.iso.as_mut().ok_or_else(unprepared)?;
        let (frame, ms) = iso.cast_display(
            &self.ctx,
            volume,
            placed,
            &panel.views[0],
            rays,
            packed,
            &desc,
            settings,
            method,
            (&self.raycast, watch),
        )?;
        self.last_pass_ms = ms;
        Ok(frame)
    }

    /// The bands this adapter casts a frame of `size` in: the units a
    /// watched GPU pass over it counts.
    pub fn band_count(&self, size: UVec2) -> u64 {
        raycast::band_count(&self.ctx, size)
    }

    /// Checks an isosurface cast of `placed`, uploads its volume and makes
    /// the isosurface pass if there is none yet.
    fn iso_ready(
        &mut self,
        placed: &PlacedVolume,
        desc: &FrameDesc,
        settings: &IsoSettings,
    ) -> Result<(), RenderError> {
        desc.validate()?;
        settings.validate()?;
        let scene = self.check_iso(placed)?;
        self.ctx.check_frame(desc)?;
        self.scene.upload(&self.ctx, &scene)?;
        if self.iso.is_none() {
            self.iso = Some(IsoPass::new(&self.ctx, &self.raycast)?);
        }
        Ok(())
    }
}

impl Render for &mut GpuRenderer {
    /// Cast in bands of rows (about 2^18 pixels each), each its own
    /// submission, each counted once the GPU has finished it: once the
    /// stop flag is set no further band starts, and
    /// `RenderError::Stopped` is returned.
    fn render_until<'w>(
        self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
        watch: impl Into<Watch<'w>>,
    ) -> Result<Frame, RenderError> {
        self.begin(scene, rays, settings, desc)?;
        let ms = self
            .raycast
            .cast(&self.ctx, scene, settings, desc.size, watch.into())?;
        self.last_pass_ms = ms;
        self.raycast.read_frame(&self.ctx, desc, scene)
    }
}
