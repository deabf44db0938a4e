//! Renderer options shared by `render` and `bench`, and the one parser
//! each for `--shading` and `--backend`.

use anari_library_caveray::cave::View;
use anari_library_caveray::geometry::{pinhole_from_matrices, MatrixCamera, PrimaryRays, RayGen};
use anari_library_caveray::render::stereo::LayerFormat;
use anari_library_caveray::render::{
    check_step_factor, Backend, RenderSettings, Renderer, Sampling, Shading,
};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Args, ValueEnum};
use glam::UVec2;

use crate::Failure;

/// `--shading` values: none, shadows, ao, shadows+ao or directional:N.
pub fn shading(s: &str) -> Result<Shading, String> {
    s.parse()
        .map_err(|e: anari_library_caveray::render::RenderError| e.to_string())
}

/// `--step-factor` values: the renderer's own check.
pub fn step_factor(s: &str) -> Result<f32, String> {
    let x = s
        .trim()
        .parse::<f32>()
        .map_err(|_| format!("expected a number, got '{s}'"))?;
    check_step_factor(x).map_err(|e| e.to_string())
}

/// `--gpu-memory-budget` values: bytes, or a number with K, M or G
/// (binary: 1K is 1024 bytes).
pub fn bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (digits, unit) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&t[..i], c.to_ascii_uppercase()),
        _ => (t, 'B'),
    };
    let shift = match unit {
        'B' => 0,
        'K' => 10,
        'M' => 20,
        'G' => 30,
        _ => {
            return Err(format!(
                "expected bytes, or a number with K, M or G, got '{s}'"
            ))
        }
    };
    digits
        .trim()
        .parse::<u64>()
        .ok()
        .and_then(|n| n.checked_mul(1 << shift))
        .filter(|&n| n > 0)
        .ok_or_else(|| format!("expected a positive number of bytes (e.g. 6G), got '{s}'"))
}

/// `--layer-format` values, listed in the help and checked by clap.
pub fn layer_format() -> impl TypedValueParser<Value = LayerFormat> {
    PossibleValuesParser::new(LayerFormat::NAMES).try_map(|s| s.parse::<LayerFormat>())
}

/// `--backend` values, listed in the help and checked by clap.
pub fn backend() -> impl TypedValueParser<Value = Backend> {
    PossibleValuesParser::new(Backend::NAMES).try_map(|s| s.parse::<Backend>())
}

#[derive(Args)]
pub struct RenderOptions {
    /// Which camera model turns each view into rays.
    #[arg(long, value_enum, default_value_t = Strategy::Offaxis)]
    pub strategy: Strategy,
    /// none, shadows, ao, shadows+ao or directional:N.
    #[arg(long, default_value = "none", value_parser = shading)]
    pub shading: Shading,
    /// gpu, cpu, or auto (a hardware GPU where there is one, else the CPU).
    #[arg(long, default_value = "auto", value_parser = backend())]
    pub backend: Backend,
    /// Step length in units of half the smallest voxel (1/64 to 64).
    #[arg(long, default_value_t = 1.0, value_parser = step_factor)]
    pub step_factor: f32,
    /// How the GPU reads samples: exact (the reference's arithmetic) or
    /// filtered (hardware trilinear and a stepped table).
    #[arg(long, default_value = "exact", value_parser = PossibleValuesParser::new(Sampling::NAMES).try_map(|s| s.parse::<Sampling>()))]
    pub gpu_sampling: Sampling,
    /// Bytes of volume textures the GPU may hold (e.g. 6G); a scene past
    /// it is refused, or with --backend auto rendered on the CPU. Default:
    /// what the GPU's driver allows.
    #[arg(long, value_parser = bytes)]
    pub gpu_memory_budget: Option<u64>,
}

impl Default for RenderOptions {
    /// The options as the command line's defaults set them.
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Only {
            #[command(flatten)]
            options: RenderOptions,
        }
        <Only as clap::Parser>::parse_from(["caveray"]).options
    }
}

impl RenderOptions {
    pub fn settings(&self) -> RenderSettings {
        RenderSettings {
            shading: self.shading,
            step_factor: self.step_factor,
            sampling: self.gpu_sampling,
            ..Default::default()
        }
    }

    /// The chosen renderer, saying so (and why the GPU is missing) on stderr.
    pub fn renderer(&self) -> Result<Renderer, Failure> {
        let (renderer, missing) =
            Renderer::choose(self.backend).map_err(|e| match self.backend {
                Backend::Gpu => Failure::Runtime(format!("{e} (try --backend cpu)")),
                _ => Failure::Runtime(e.to_string()),
            })?;
        if let Some(why) = missing {
            eprintln!("caveray: {why}");
        }
        let mut renderer = renderer;
        renderer.set_gpu_budget(self.gpu_memory_budget);
        eprintln!("caveray: rendering on {}", renderer.describe());
        Ok(renderer)
    }
}

/// The camera models of docs/off_axis.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Strategy {
    /// Strategy 1: rays from the inverse of the f32 OpenGL matrices.
    Matrix,
    /// Strategy 2: a pinhole at the eye plus an image region.
    Pinhole,
    /// Strategy 3: a pinhole recovered from the f32 matrices.
    FromMatrices,
    /// The native off-axis camera: wall corners and eye.
    Offaxis,
}

impl Strategy {
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Matrix => "matrix",
            Strategy::Pinhole => "pinhole",
            Strategy::FromMatrices => "from-matrices",
            Strategy::Offaxis => "offaxis",
        }
    }

    /// The view's rays for an image of `size`. The matrix strategies get
    /// single-precision matrices, as an OpenGL host hands them over.
    pub fn rays(self, view: &View, size: UVec2) -> Result<RayGen, String> {
        let e = |e: anari_library_caveray::geometry::GeometryError| e.to_string();
        let (v, p) = (
            view.projection.view.as_mat4(),
            view.projection.proj.as_mat4(),
        );
        Ok(match self {
            Strategy::Matrix => MatrixCamera::from_f32(v, p).map_err(e)?.ray_gen(size),
            Strategy::Pinhole => view.pinhole().map_err(e)?.ray_gen(size),
            Strategy::FromMatrices => pinhole_from_matrices(v.as_dmat4(), p.as_dmat4())
                .map_err(e)?
                .camera
                .ray_gen(size),
            Strategy::Offaxis => view.camera.ray_gen(size),
        })
    }
}
