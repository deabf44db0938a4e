//! `caveray bench raycast`: the paper's ray-casting setup (its protocol
//! constants and focal length come from the stereo planner) on the GPU and
//! the CPU reference. Timings are wall-clock per frame, read-back
//! included, after a warm-up frame; the GPU's pass times come beside them.

use std::path::PathBuf;
use std::time::Instant;

use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays, RayGen};
use anari_library_caveray::render::stereo::{paper, HmdStereo};
use anari_library_caveray::render::{Backend, FrameDesc, RenderSettings, Renderer, Shading};
use anari_library_caveray::scene::Scene;
use clap::Args;
use glam::{DVec3, UVec2, Vec3};
use serde::Serialize;

use super::mean;
use crate::options::shading;
use crate::progress::Progress;
use crate::report::{write_json, Machine, RendererInfo, VolumeInfo};
use crate::scene::VolumeArgs;
use crate::Failure;

#[derive(Args)]
pub struct RaycastArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    /// Image width and height in pixels.
    #[arg(long, default_value_t = paper::WIDTH)]
    size: u32,
    /// Shading modes to sweep, comma-separated (none, shadows, ao,
    /// shadows+ao, directional:N).
    #[arg(long, default_value = "none", value_delimiter = ',', value_parser = shading)]
    shading: Vec<Shading>,
    /// Views in the 360 degree rotation.
    #[arg(long, default_value_t = paper::VIEWS)]
    steps: u32,
    /// Of those, how many (evenly spread) the CPU reference renders; the
    /// ratio compares the same views. 0 skips the CPU.
    #[arg(long, default_value_t = 5)]
    cpu_steps: u32,
    /// Skip the GPU (e.g. to time the CPU reference alone).
    #[arg(long)]
    no_gpu: bool,
    /// Where to write the results.
    #[arg(long)]
    json: PathBuf,
}

#[derive(Serialize)]
struct RaycastReport {
    benchmark: &'static str,
    machine: Machine,
    volume: VolumeInfo,
    image: [u32; 2],
    fov_degrees: f64,
    focal_length_m: f64,
    bounding_radius_m: f64,
    steps: u32,
    cpu_views: Vec<usize>,
    runs: Vec<RaycastRun>,
}

#[derive(Serialize)]
struct RaycastRun {
    shading: String,
    extra_samples_per_sample: u32,
    results: Results,
    /// Mean CPU time over mean GPU time on the views both rendered.
    cpu_over_gpu_same_views: Option<f64>,
}

#[derive(Default, Serialize)]
struct Results {
    #[serde(skip_serializing_if = "Option::is_none")]
    gpu: Option<Timings>,
    #[serde(skip_serializing_if = "Option::is_none")]
    cpu: Option<Timings>,
}

#[derive(Serialize)]
struct Timings {
    renderer: RendererInfo,
    views: Vec<usize>,
    ms: Vec<f64>,
    mean_ms: f64,
    min_ms: f64,
    /// The GPU's ray casting pass alone, by its pass clock.
    #[serde(skip_serializing_if = "Option::is_none")]
    pass_ms: Option<Vec<f64>>,
    rays_per_s: f64,
    samples_per_s: f64,
}

/// One timed view: index, wall-clock ms, GPU pass ms, samples.
struct Timed {
    view: usize,
    ms: f64,
    pass_ms: Option<f64>,
    samples: u64,
}

pub fn run(args: RaycastArgs) -> Result<(), Failure> {
    if args.size == 0 || args.steps == 0 || args.cpu_steps > args.steps {
        return Err(Failure::Usage(format!(
            "need --size > 0, --steps > 0 and --cpu-steps <= --steps (got {}, {}, {})",
            args.size, args.steps, args.cpu_steps
        )));
    }
    let loaded = args.volume.load()?;
    FrameDesc::new(glam::UVec2::splat(args.size))
        .validate()
        .map_err(|e| Failure::Usage(format!("--size {}: {e}", args.size)))?;
    let setup = HmdStereo::protocol(args.size, paper::SPAN_PX);
    let radius = setup.radius.unwrap_or(paper::RADIUS_M);
    // Longest side such that the bounding sphere has the protocol's radius.
    let (lo, hi) = loaded.volume.bounds();
    let extent = hi - lo;
    let size = extent.max_element() * (2.0 * radius as f32) / extent.length();
    let scene = loaded.placed(Vec3::ZERO, size)?;
    let image = UVec2::splat(args.size);
    let cameras = (0..args.steps)
        .map(|i| camera(i, args.steps, &setup, radius, image))
        .collect::<Result<Vec<_>, _>>()?;

    let mut renderers = Vec::new();
    if !args.no_gpu {
        let gpu = Renderer::new(Backend::Gpu).map_err(|e| {
            Failure::Runtime(format!(
                "{e} (use --no-gpu to time the CPU reference alone)"
            ))
        })?;
        renderers.push(gpu);
    }
    if args.cpu_steps > 0 {
        renderers.push(Renderer::new(Backend::Cpu).map_err(|e| Failure::Runtime(e.to_string()))?);
    }
    let cpu_views: Vec<usize> = (0..args.cpu_steps)
        .map(|i| (i * args.steps / args.cpu_steps.max(1)) as usize)
        .collect();
    let views_of = |r: &Renderer| match r.backend() {
        Backend::Cpu => cpu_views.clone(),
        _ => (0..cameras.len()).collect::<Vec<_>>(),
    };
    let total: usize = renderers
        .iter()
        .map(|r| views_of(r).len() + usize::from(r.backend() == Backend::Gpu))
        .sum::<usize>()
        * args.shading.len();
    let mut progress = Progress::new(total);

    let mut runs = Vec::new();
    for shading in &args.shading {
        let settings = RenderSettings {
            shading: *shading,
            ..Default::default()
        };
        let mut results = Results::default();
        for renderer in &mut renderers {
            let backend = renderer.backend();
            let name = backend.name();
            if backend == Backend::Gpu {
                renderer
                    .upload(&scene)
                    .map_err(|e| Failure::Runtime(e.to_string()))?;
                time_view(renderer, 0, &scene, &cameras[0], &settings, image)?;
                progress.step(&format!("{name} {shading} warm-up"));
            }
            let mut timed = Vec::new();
            for i in views_of(renderer) {
                let t = time_view(renderer, i, &scene, &cameras[i], &settings, image)?;
                progress.step(&format!("{name} {shading} view {i} {:.1} ms", t.ms));
                timed.push(t);
            }
            let timings = Some(summary(renderer, &timed, image));
            match backend {
                Backend::Cpu => results.cpu = timings,
                _ => results.gpu = timings,
            }
        }
        runs.push(RaycastRun {
            shading: shading.to_string(),
            extra_samples_per_sample: shading.extra_samples(),
            cpu_over_gpu_same_views: speedup(&results, &cpu_views),
            results,
        });
    }

    let report = RaycastReport {
        benchmark: "raycast",
        machine: Machine::this(),
        volume: VolumeInfo::of(&loaded.name, &scene),
        image: [args.size, args.size],
        fov_degrees: setup.fov.to_degrees(),
        focal_length_m: setup.focal,
        bounding_radius_m: radius,
        steps: args.steps,
        cpu_views,
        runs,
    };
    write_json(&report, &args.json)?;
    print_report(&report);
    Ok(())
}

/// View `i` of `n` around the y axis: the eye at distance h + r from the
/// volume's centre, so the bounding sphere's near point is h away.
fn camera(i: u32, n: u32, setup: &HmdStereo, radius: f64, image: UVec2) -> Result<RayGen, Failure> {
    let angle = std::f64::consts::TAU * f64::from(i) / f64::from(n);
    let position = (setup.focal + radius) * DVec3::new(angle.sin(), 0.0, angle.cos());
    PinholeCamera::new(
        position,
        -position,
        DVec3::Y,
        setup.fov,
        1.0,
        ImageRegion::FULL,
    )
    .map(|c| c.ray_gen(image))
    .map_err(|e| Failure::Runtime(e.to_string()))
}

fn time_view(
    renderer: &mut Renderer,
    view: usize,
    scene: &Scene,
    rays: &RayGen,
    settings: &RenderSettings,
    size: UVec2,
) -> Result<Timed, Failure> {
    let t = Instant::now();
    let frame = renderer
        .render(scene, rays, settings, &FrameDesc::new(size))
        .map_err(|e| Failure::Runtime(e.to_string()))?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let pass_ms = match renderer {
        Renderer::Gpu(g) => Some(g.last_pass_ms()),
        Renderer::Cpu(_) => None,
    };
    Ok(Timed {
        view,
        ms,
        pass_ms,
        samples: frame.samples,
    })
}

fn summary(renderer: &Renderer, timed: &[Timed], size: UVec2) -> Timings {
    let ms: Vec<f64> = timed.iter().map(|t| t.ms).collect();
    let total_s = ms.iter().sum::<f64>() / 1e3;
    let samples: u64 = timed.iter().map(|t| t.samples).sum();
    Timings {
        renderer: RendererInfo::of(renderer),
        views: timed.iter().map(|t| t.view).collect(),
        mean_ms: mean(ms.iter().copied()),
        min_ms: ms.iter().copied().fold(f64::INFINITY, f64::min),
        pass_ms: timed.iter().map(|t| t.pass_ms).collect(),
        rays_per_s: f64::from(size.x * size.y) * timed.len() as f64 / total_s,
        samples_per_s: samples as f64 / total_s,
        ms,
    }
}

fn speedup(results: &Results, cpu_views: &[usize]) -> Option<f64> {
    let (gpu, cpu) = (results.gpu.as_ref()?, results.cpu.as_ref()?);
    let same = cpu_views.iter().filter_map(|&i| gpu.ms.get(i).copied());
    Some(cpu.mean_ms / mean(same))
}

fn print_report(report: &RaycastReport) {
    println!(
        "raycast {} at {}x{}, {} views about y ({} on the CPU), machine: {}",
        report.volume.name,
        report.image[0],
        report.image[1],
        report.steps,
        report.cpu_views.len(),
        report.machine.cpu
    );
    println!(
        "{:<15} {:<8} {:>10} {:>10} {:>10} {:>12} {:>10}",
        "shading", "backend", "mean ms", "min ms", "pass ms", "Msamples/s", "CPU/GPU"
    );
    for run in &report.runs {
        for (name, r) in [("gpu", &run.results.gpu), ("cpu", &run.results.cpu)] {
            let Some(r) = r else { continue };
            let ratio = match (name, run.cpu_over_gpu_same_views) {
                ("cpu", Some(x)) => format!("{x:.2}"),
                _ => String::new(),
            };
            let pass = r
                .pass_ms
                .as_ref()
                .map_or(String::new(), |p| format!("{:.1}", mean(p.iter().copied())));
            println!(
                "{:<15} {:<8} {:>10.1} {:>10.1} {:>10} {:>12.1} {:>10}",
                run.shading,
                name,
                r.mean_ms,
                r.min_ms,
                pass,
                r.samples_per_s / 1e6,
                ratio
            );
        }
    }
    let adapter = report
        .runs
        .first()
        .and_then(|run| run.results.gpu.as_ref())
        .and_then(|g| g.renderer.adapter());
    if let Some(a) = adapter {
        println!(
            "GPU adapter: {} ({}); pass times by {}",
            a.name,
            a.api,
            a.pass_clock.name()
        );
    }
}
