//! `caveray bench`: speed measurements that write JSON (from typed
//! reports, which the printed tables and the charts read too) and print a
//! summary. Compare timings only as ratios taken in one run.

mod autostereo;
mod bumpy;
mod cave_stereo;
mod charts;
mod check;
mod raycast;
mod stereo;
mod stream;
mod surfaces;

use anari_library_caveray::render::stereo::RenderFacts;
use clap::Subcommand;

use crate::{report, Failure};

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Buchacher & Erdt's ray-casting setup: 768^2, 110 degree field of view,
    /// volume scaled to a 1 m bounding radius, 360 degrees about y.
    Raycast(raycast::RaycastArgs),
    /// Single-pass stereo by re-projection against rendering both eyes,
    /// by Buchacher & Erdt's protocol (writes JSON, an SVG plot and heat maps).
    Stereo(stereo::StereoBenchArgs),
    /// Single-pass stereo on every wall of a CAVE along a head path: the
    /// share of wall-frames re-projected, V and DSSIM per wall (writes
    /// JSON, plots over time and the worst wall-frame's heat map).
    CaveStereo(cave_stereo::CaveStereoArgs),
    /// A multi-view display's image, every subpixel from its own eye:
    /// naive (every view, then interleaved) against per subpixel, for
    /// several view counts (writes JSON, prints a table).
    Autostereo(autostereo::AutostereoArgs),
    /// A triangle mesh (a volume's isosurface, --mesh) alone and inside
    /// its volume, or the C mesh benchmark's million triangles (--bumpy),
    /// on the GPU and the CPU: BVH build, bytes per triangle, first and
    /// later frames, GPU against CPU (writes JSON, prints a table).
    Surfaces(surfaces::SurfacesArgs),
    /// A volume past the GPU memory budget, paged: a complete frame
    /// within the budget, then frames that do not wait for the loader
    /// converging to it (writes JSON, a chart and a strip of frames).
    Stream(stream::StreamArgs),
    /// The ratios that define caveray (stereo pair against one eye,
    /// packets against scalar, skipping on against off, ...) at tiny
    /// sizes, against the committed baseline: fails where one is worse
    /// than its margin or crosses its limit (writes JSON, prints a table).
    Check(check::CheckArgs),
}

pub fn run(command: BenchCommand) -> Result<(), Failure> {
    without_shader_cache();
    match command {
        BenchCommand::Raycast(args) => raycast::run(args),
        BenchCommand::Stereo(args) => stereo::run(args),
        BenchCommand::CaveStereo(args) => cave_stereo::run(args),
        BenchCommand::Autostereo(args) => autostereo::run(args),
        BenchCommand::Surfaces(args) => surfaces::run(args),
        BenchCommand::Stream(args) => stream::run(args),
        BenchCommand::Check(args) => check::run(args),
    }
}

/// Times shaders as a fresh machine compiles them: Mesa's on-disk shader
/// cache would hand a run what an earlier run compiled, so that lavapipe's
/// figures would depend on the runs before. The caller's own setting wins;
/// other drivers ignore the variable. Set before any GPU is opened, while
/// the tool runs one thread.
fn without_shader_cache() {
    if std::env::var_os(report::SHADER_CACHE_VAR).is_none() {
        std::env::set_var(report::SHADER_CACHE_VAR, "true");
    }
}

/// What the stereo benchmarks' renderer brings to the re-projection
/// decision: the GPU's pass, over the background color.
const GPU: RenderFacts = RenderFacts {
    reprojects: true,
    background_image: false,
    hits: false,
};

fn mean(v: impl IntoIterator<Item = f64>) -> f64 {
    let (sum, n) = v
        .into_iter()
        .fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    sum / n.max(1) as f64
}

fn runtime(e: impl std::fmt::Display) -> Failure {
    Failure::Runtime(e.to_string())
}
