//! Volume ray casting: the wgpu renderer, the CPU renderer (with the
//! scalar reference both are checked against), and what they share (settings, frame formats, the march plan).

pub mod cells;
mod compare;
pub mod cpu;
pub mod empty_space;
pub mod encoding;
mod frame;
pub mod gpu;
mod hits;
pub mod iso;
mod march_plan;
mod progress;
mod settings;
pub mod shapes;
pub mod simd;
pub mod stereo;
pub mod warp;

use std::sync::atomic::AtomicBool;

use thiserror::Error;

pub use compare::{dssim, ssim, ssim_map, SsimMap, SSIM_WINDOW};
pub use cpu::CpuRenderer;
pub use frame::{ColorData, ColorFormat, Frame, FrameDesc, MAX_FRAME_PIXELS};
pub use gpu::{GpuRenderer, PassClock, StreamWait, Streaming, Uploads};
pub use hits::{HitChannel, HitRecord, PixelHit};
pub use progress::{Done, Progress, Watch};
pub use settings::{
    check_step_factor, BackgroundImage, ClipPlanes, Lamp, Part, RenderSettings, Sampling, Shading,
    Spot, SurfaceShading, LOD_MAX, MAX_CLIP_PLANES, MAX_DIRECTIONS, MAX_LAMPS, MAX_STEPS_PER_RAY,
    STEP_FACTOR_RANGE,
};

use crate::geometry::RayGen;
use crate::scene::Scene;
use simd::Level;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum RenderError {
    #[error("{0}")]
    Settings(String),
    #[error("no usable Vulkan adapter: {0}")]
    NoAdapter(String),
    #[error(
        "volume of {}x{}x{} voxels exceeds the largest 3D texture {adapter} allows ({max} per side)",
        .dims[0], .dims[1], .dims[2]
    )]
    VolumeTooLarge {
        dims: [u32; 3],
        max: u32,
        adapter: String,
    },
    #[error("frame of {}x{} is too large for {adapter}: {reason}", .size[0], .size[1])]
    FrameTooLarge {
        size: [u32; 2],
        reason: String,
        adapter: String,
    },
    #[error("GPU error: {0}")]
    Gpu(String),
    #[error("the render was stopped before it finished")]
    Stopped,
    #[error("cannot allocate {bytes} bytes for {what}")]
    OutOfMemory { bytes: u64, what: String },
}

impl RenderError {
    /// Whether the scene is too large for this renderer (another may
    /// render it).
    pub fn is_size(&self) -> bool {
        matches!(
            self,
            RenderError::VolumeTooLarge { .. } | RenderError::OutOfMemory { .. }
        )
    }
}

/// Why some primary rays of `scene` under `settings` stop before they
/// have crossed it, if any would: the scene's diagonal takes more than
/// MAX_STEPS_PER_RAY steps (one volume much finer than the scene is
/// wide, or a very small step factor).
pub fn march_warning(scene: &Scene, settings: &RenderSettings) -> Option<String> {
    let plan = march_plan::MarchPlan::new(scene, &RayGen::default(), settings).ok()?;
    plan.cut_short.then(|| {
        let (lo, hi) = scene.bounds();
        format!(
            "rays are cut at {} steps of {:.3e}: the scene's diagonal ({:.3e}) takes more; raise the step factor or drop the finest volume",
            plan.max_steps,
            plan.step,
            (hi - lo).length()
        )
    })
}

/// Which implementation renders: what the tool's `--backend`, the
/// device's `backend` parameter and `$CAVERAY_BACKEND` choose from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backend {
    /// The GPU where a hardware adapter opens, else the CPU.
    #[default]
    Auto,
    Gpu,
    Cpu,
}

impl Backend {
    pub const NAMES: [&'static str; 3] = ["auto", "gpu", "cpu"];

    pub fn name(self) -> &'static str {
        match self {
            Backend::Auto => "auto",
            Backend::Gpu => "gpu",
            Backend::Cpu => "cpu",
        }
    }
}

impl std::str::FromStr for Backend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Backend::Auto),
            "gpu" => Ok(Backend::Gpu),
            "cpu" => Ok(Backend::Cpu),
            _ => Err(format!("unknown backend '{s}'; expected auto, gpu or cpu")),
        }
    }
}

/// Bytes a scene's volumes take in host memory and on the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Residency {
    pub host: u64,
    pub gpu: u64,
}

/// Why `Backend::Auto` rendered on the CPU.
#[derive(Debug)]
pub enum AutoChoice {
    /// No Vulkan adapter opened.
    NoGpu(RenderError),
    /// The best adapter is this software one, slower than the CPU path.
    SoftwareAdapter(String),
    /// The GPU cannot hold the scene.
    TooLarge(RenderError),
}

impl std::fmt::Display for AutoChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AutoChoice::NoGpu(e) => write!(f, "no GPU ({e}); rendering on the CPU"),
            AutoChoice::SoftwareAdapter(name) => write!(
                f,
                "the only Vulkan adapter is {name}, which runs on the CPU: the CPU renderer is faster here, so it renders (backend 'gpu' takes the adapter anyway)"
            ),
            AutoChoice::TooLarge(e) => write!(f, "{e}; rendering on the CPU"),
        }
    }
}

/// Renders frames of a scene: the CPU's renderer, the GPU's, and
/// [`Renderer`] (either). Implemented for references (`&CpuRenderer`,
/// `&mut GpuRenderer`, `&mut Renderer`), since the CPU renders through a
/// shared reference and the GPU through an exclusive one; call it on the
/// renderer as a method either way.
pub trait Render: Sized {
    /// A frame of `scene` through `rays`, giving up with
    /// `RenderError::Stopped` once the watch's stop flag is set (a bare
    /// `&AtomicBool` will do), counting into its [`Progress`]: CPU tiles,
    /// GPU bands.
    fn render_until<'w>(
        self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
        watch: impl Into<Watch<'w>>,
    ) -> Result<Frame, RenderError>;

    /// A frame of `scene` through `rays`.
    fn render(
        self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
    ) -> Result<Frame, RenderError> {
        self.render_until(scene, rays, settings, desc, &AtomicBool::new(false))
    }
}

/// The GPU renderer where a hardware adapter exists, else the CPU's.
pub enum Renderer {
    Gpu(Box<GpuRenderer>),
    Cpu(CpuRenderer),
}

impl Renderer {
    /// The renderer `backend` names; `Backend::Gpu` fails if no adapter
    /// can be opened. See [`Renderer::choose`] for what `Auto` picks.
    pub fn new(backend: Backend) -> Result<Self, RenderError> {
        Self::choose(backend).map(|(r, _)| r)
    }

    /// The renderer `backend` names and, where `Auto` chose the CPU, why:
    /// no Vulkan adapter opens, or the best one is software (llvmpipe),
    /// where the CPU renderer is the faster of the two (README, Measured).
    pub fn choose(backend: Backend) -> Result<(Self, Option<AutoChoice>), RenderError> {
        Ok(match backend {
            Backend::Gpu => (Renderer::Gpu(Box::new(GpuRenderer::new()?)), None),
            Backend::Cpu => (Renderer::Cpu(CpuRenderer::new()), None),
            Backend::Auto => match GpuRenderer::probe() {
                Ok(info) if info.device_type == wgpu::DeviceType::Cpu => (
                    Renderer::Cpu(CpuRenderer::new()),
                    Some(AutoChoice::SoftwareAdapter(info.name)),
                ),
                Ok(_) => match GpuRenderer::new() {
                    Ok(gpu) => (Renderer::Gpu(Box::new(gpu)), None),
                    Err(e) => (
                        Renderer::Cpu(CpuRenderer::new()),
                        Some(AutoChoice::NoGpu(e)),
                    ),
                },
                Err(e) => (
                    Renderer::Cpu(CpuRenderer::new()),
                    Some(AutoChoice::NoGpu(e)),
                ),
            },
        })
    }

    /// `Gpu` or `Cpu`: what renders, never `Auto`.
    pub fn backend(&self) -> Backend {
        match self {
            Renderer::Gpu(_) => Backend::Gpu,
            Renderer::Cpu(_) => Backend::Cpu,
        }
    }

    /// A one-line description: adapter name and graphics API, or the CPU.
    pub fn describe(&self) -> String {
        match self {
            Renderer::Gpu(g) => {
                let info = g.adapter();
                format!(
                    "GPU: {} ({:?}, {} {})",
                    info.name, info.backend, info.driver, info.driver_info
                )
            }
            Renderer::Cpu(c) => format!(
                "CPU ({} threads{})",
                rayon::current_num_threads(),
                match c.packet_level() {
                    Some(Level::Avx512) => ", AVX-512 packets",
                    Some(_) => ", AVX2 packets",
                    None => ", scalar",
                }
            ),
        }
    }

    /// Puts the scene where the renderer reads it (GPU memory), so that
    /// the next frames time rendering alone.
    pub fn upload(&mut self, scene: &Scene) -> Result<(), RenderError> {
        match self {
            Renderer::Gpu(g) => g.upload(scene),
            Renderer::Cpu(_) => Ok(()),
        }
    }

    /// Where `backend` is `Auto` and the GPU cannot hold one of
    /// `surfaces`' fields (longer than its textures, or past its memory
    /// budget), this becomes the CPU renderer, which can, and says why.
    pub fn fit_surfaces(
        &mut self,
        backend: Backend,
        surfaces: &[iso::IsoSurface],
    ) -> Option<AutoChoice> {
        let Renderer::Gpu(g) = self else {
            return None;
        };
        let refused = surfaces
            .iter()
            .find_map(|s| g.check_iso(&s.placed).err())
            .filter(|e| backend == Backend::Auto && e.is_size())?;
        *self = Renderer::Cpu(CpuRenderer::new());
        Some(AutoChoice::TooLarge(refused))
    }

    /// At most `bytes` of volume textures on the GPU (None: what the
    /// driver allows); the CPU has no such budget.
    pub fn set_gpu_budget(&mut self, bytes: Option<u64>) {
        if let Renderer::Gpu(g) = self {
            g.set_memory_budget(bytes);
        }
    }

    /// How long a GPU frame waits for the bricks of paged volumes
    /// ([`GpuRenderer::set_stream_wait`]); the CPU reads every voxel
    /// where it lies.
    pub fn set_stream_wait(&mut self, wait: StreamWait) {
        if let Renderer::Gpu(g) = self {
            g.set_stream_wait(wait);
        }
    }

    /// The share of the bricks the last frame selected that it rendered
    /// with (1 where nothing is paged, and on the CPU).
    pub fn stream_progress(&self) -> f32 {
        match self {
            Renderer::Gpu(g) => g.streaming().progress(),
            Renderer::Cpu(_) => 1.0,
        }
    }

    /// [`Renderer::upload`], except that where `backend` is `Auto` and the
    /// GPU cannot hold the scene (a volume past its textures or its
    /// memory), this becomes the CPU renderer, which can, and says why.
    pub fn upload_for(
        &mut self,
        backend: Backend,
        scene: &Scene,
    ) -> Result<Option<AutoChoice>, RenderError> {
        match self.upload(scene) {
            Err(e) if backend == Backend::Auto && e.is_size() => {
                *self = Renderer::Cpu(CpuRenderer::new());
                Ok(Some(AutoChoice::TooLarge(e)))
            }
            other => other.map(|()| None),
        }
    }

    /// Bytes `scene`'s volumes hold where this renderer reads them, each
    /// grid once: their stored voxels in host memory (none for a host's
    /// shared array read in place), and the CPU's f32
    /// copies for its packets, or the GPU's textures (and for paged
    /// volumes their pools, and the coarser levels the host keeps).
    pub fn resident_bytes(&self, scene: &Scene) -> Residency {
        let host: u64 = scene.grids().map(|v| v.held_bytes()).sum();
        match self {
            Renderer::Gpu(g) => Residency {
                host: host + g.host_volume_bytes(),
                gpu: g.volume_bytes(),
            },
            Renderer::Cpu(c) => Residency {
                host: host + c.copy_bytes(scene),
                gpu: 0,
            },
        }
    }

    /// What warps need of a view (color over nothing, first-hit depth and
    /// `layers` layers a pixel), and the milliseconds it took: the GPU's
    /// pass clock, or the CPU's wall clock. Counts rows on the CPU, bands
    /// on the GPU.
    #[allow(clippy::too_many_arguments)]
    pub fn capture<'w>(
        &mut self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        size: glam::UVec2,
        layers: usize,
        watch: impl Into<Watch<'w>>,
    ) -> Result<(warp::Source, f64), RenderError> {
        let watch = watch.into();
        match self {
            Renderer::Gpu(g) => g.capture(scene, rays, settings, size, layers, watch),
            Renderer::Cpu(c) => {
                let clock = std::time::Instant::now();
                let source = c.capture(scene, rays, settings, size, layers, watch)?;
                Ok((source, clock.elapsed().as_secs_f64() * 1e3))
            }
        }
    }

    /// `source` shown from `target` by `settings.mode`, on this renderer's
    /// hardware, and the milliseconds it took.
    pub fn warp(
        &mut self,
        source: &warp::Source,
        target: &RayGen,
        size: glam::UVec2,
        settings: &warp::WarpSettings,
    ) -> Result<(warp::Warped, f64), RenderError> {
        match self {
            Renderer::Gpu(g) => g.warp(source, target, size, settings),
            Renderer::Cpu(_) => {
                let clock = std::time::Instant::now();
                let warped = warp::warp(source, target, size, settings)?;
                Ok((warped, clock.elapsed().as_secs_f64() * 1e3))
            }
        }
    }

    /// `surfaces` seen through `rays`, the nearest per pixel: the CPU
    /// reference's caster (which looks at the stop flag and counts between
    /// rows) or the GPU's (between bands of rows), every surface's units
    /// announced before the first is cast.
    pub fn cast_surfaces<'w>(
        &mut self,
        surfaces: &[iso::IsoSurface],
        rays: &RayGen,
        desc: &FrameDesc,
        watch: impl Into<Watch<'w>>,
    ) -> Result<Frame, RenderError> {
        let watch = watch.into();
        let one = FrameDesc {
            depth: desc.depth || surfaces.len() > 1,
            ..*desc
        };
        watch.expect(self.cast_units(desc.size) * surfaces.len() as u64);
        let part = watch.part();
        let mut frames = Vec::with_capacity(surfaces.len());
        for s in surfaces {
            frames.push(match self {
                Renderer::Gpu(g) => g.cast_iso(&s.placed, rays, &one, &s.settings, part)?,
                Renderer::Cpu(c) => {
                    s.settings.validate()?;
                    let (values, bounds) = c.iso_field(&s.placed, &s.settings)?;
                    let caster = iso::Caster::with_bounds(&s.placed, &values, &s.settings, bounds)
                        .watched(part);
                    iso::cast_by(&caster, rays, &one)?.0
                }
            });
        }
        match frames.len() {
            0 => Err(RenderError::Settings("no surface to cast".into())),
            1 => Ok(frames.remove(0)),
            _ => iso::nearest(frames, desc),
        }
    }

    /// A multi-view panel's image of `surface` by `method`, watched as
    /// `cast_surfaces` is: every pass's rows (CPU) or bands (GPU); the
    /// GPU's naive way is a cast per view, interleaved.
    pub fn cast_display<'w>(
        &mut self,
        surface: &iso::IsoSurface,
        panel: &iso::Panel,
        method: iso::MultiViewMethod,
        watch: impl Into<Watch<'w>>,
    ) -> Result<Frame, RenderError> {
        let watch = watch.into();
        let (placed, settings) = (&surface.placed, &surface.settings);
        match self {
            Renderer::Gpu(g) if method == iso::MultiViewMethod::Naive => {
                // Views in floats: an 8-bit panel is quantised once.
                let desc = FrameDesc::new(panel.size).with_color(ColorFormat::Rgba32F);
                watch.expect(g.band_count(panel.size) * panel.views.len() as u64);
                let mut views = Vec::with_capacity(panel.views.len());
                for rays in &panel.views {
                    views.push(g.cast_iso(placed, rays, &desc, settings, watch.part())?);
                }
                iso::interleave(&views, panel)
            }
            Renderer::Gpu(g) => g.cast_display(placed, panel, settings, method, watch),
            Renderer::Cpu(c) => {
                settings.validate()?;
                let (values, bounds) = c.iso_field(placed, settings)?;
                let caster =
                    iso::Caster::with_bounds(placed, &values, settings, bounds).watched(watch);
                Ok(iso::render_display_by(&caster, panel, method)?.0)
            }
        }
    }

    /// The units one isosurface cast of an image of `size` counts: its
    /// rows on the CPU, its bands on the GPU.
    fn cast_units(&self, size: glam::UVec2) -> u64 {
        match self {
            Renderer::Gpu(g) => g.band_count(size),
            Renderer::Cpu(_) => u64::from(size.y),
        }
    }
}

impl Render for &mut Renderer {
    /// The CPU reference checks the stop flag between pixels and counts
    /// tiles; the GPU checks it and counts between bands of rows (about
    /// 2^18 pixels each).
    fn render_until<'w>(
        self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
        watch: impl Into<Watch<'w>>,
    ) -> Result<Frame, RenderError> {
        let watch = watch.into();
        let frame = match self {
            Renderer::Gpu(g) => g.render_until(scene, rays, settings, desc, watch),
            Renderer::Cpu(c) => c.render_until(scene, rays, settings, desc, watch),
        }?;
        if watch.stopped() {
            return Err(RenderError::Stopped);
        }
        Ok(frame)
    }
}
