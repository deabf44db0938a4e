//! `caveray bench raycast`: Buchacher & Erdt's ray-casting setup (its protocol
//! constants and focal length come from the stereo planner) on the GPU and
//! the CPU, over volumes, shading modes and empty-space skipping on and
//! off, optionally beside the scalar CPU reference marching every step.
//! Timings are wall-clock per frame, read-back included, after a warm-up
//! frame; the GPU's pass times come beside them.

use std::path::PathBuf;
use std::time::Instant;

use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays, RayGen};
use anari_library_caveray::render::stereo::{paper, HmdStereo};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, Backend, CpuRenderer, Frame, FrameDesc, RenderSettings, Renderer, Sampling, Shading,
    LOD_MAX,
};
use anari_library_caveray::scene::Scene;
use clap::Args;
use glam::{DVec3, UVec2, Vec3};
use serde::Serialize;

use super::mean;
use crate::options::shading;
use crate::progress::Progress;
use crate::report::{write_json, Machine, RendererInfo, VolumeInfo};
use crate::scene::{at, protocol_frame, VolumeArgs, PROTOCOL_UNITS};
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
    /// Of those, how many (evenly spread) the CPU renders; the
    /// ratio compares the same views. 0 skips the CPU.
    #[arg(long, default_value_t = 5)]
    cpu_steps: u32,
    /// Skip the GPU (e.g. to time the CPU alone).
    #[arg(long)]
    no_gpu: bool,
    /// Empty-space skipping, comma-separated: on, off or both; with both,
    /// the speed-up and the samples skipped are reported.
    #[arg(long, default_value = "on", value_delimiter = ',', value_parser = on_off)]
    skipping: Vec<bool>,
    /// Also time the scalar CPU reference marching every step (the CPU
    /// renderer without packets or skipping) on the CPU's views.
    #[arg(long)]
    cpu_reference: bool,
    /// GPU sampling modes, comma-separated: exact, filtered; with both,
    /// the filtered images are compared with the exact ones (SSIM).
    #[arg(long, default_value = "exact", value_delimiter = ',', value_parser = gpu_sampling)]
    gpu_sampling: Vec<Sampling>,
    /// Level of detail for filtered GPU sampling (0: full detail; see the
    /// renderer's levelOfDetail); its SSIM against the exact path is the
    /// quality it costs.
    #[arg(long, default_value_t = 0.0, value_parser = lod)]
    lod: f32,
    /// Where to write the results.
    #[arg(long, default_value = "out/bench/raycast.json")]
    json: PathBuf,
}

fn lod(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(x) if (0.0..=LOD_MAX).contains(&x) => Ok(x),
        _ => Err(format!("expected a number from 0 to {LOD_MAX}, got '{s}'")),
    }
}

fn gpu_sampling(s: &str) -> Result<Sampling, String> {
    s.parse()
        .map_err(|e: anari_library_caveray::render::RenderError| e.to_string())
}

fn on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("expected on or off, got '{s}'")),
    }
}

#[derive(Serialize)]
struct RaycastReport {
    benchmark: &'static str,
    machine: Machine,
    image: [u32; 2],
    fov_degrees: f64,
    focal_length_m: f64,
    bounding_radius_m: f64,
    steps: u32,
    cpu_views: Vec<usize>,
    /// The lanes the CPU renderer's volume packets take here (avx512,
    /// avx2; none: the scalar path), as CAVERAY_SIMD may narrow them.
    cpu_packets: &'static str,
    volumes: Vec<VolumeRuns>,
}

#[derive(Serialize)]
struct VolumeRuns {
    volume: VolumeInfo,
    runs: Vec<RaycastRun>,
    /// Per shading mode and backend, where skipping ran both ways.
    skipping: Vec<SkippingGain>,
}

#[derive(Serialize)]
struct RaycastRun {
    shading: String,
    skipping: bool,
    extra_samples_per_sample: u32,
    results: Results,
    /// Mean CPU time over mean GPU time on the views both rendered.
    cpu_over_gpu_same_views: Option<f64>,
    /// Mean reference time over mean CPU time, same views.
    cpu_speedup_over_reference: Option<f64>,
    /// Filtered GPU sampling against exact: mean time ratio, and the SSIM
    /// of the first view's two images.
    #[serde(skip_serializing_if = "Option::is_none")]
    filtered_speedup: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    filtered_ssim: Option<f64>,
}

#[derive(Default, Serialize)]
struct Results {
    #[serde(skip_serializing_if = "Option::is_none")]
    gpu: Option<Timings>,
    /// The GPU with filtered sampling.
    #[serde(skip_serializing_if = "Option::is_none")]
    gpu_filtered: Option<Timings>,
    #[serde(skip_serializing_if = "Option::is_none")]
    cpu: Option<Timings>,
    /// The scalar reference, every step marched (skipping off).
    #[serde(skip_serializing_if = "Option::is_none")]
    cpu_reference: Option<Timings>,
}

#[derive(Serialize)]
struct SkippingGain {
    shading: String,
    backend: &'static str,
    /// Mean time with skipping off over with it on.
    speedup: f64,
    samples_on: u64,
    samples_off: u64,
    /// Share of the samples skipping left out.
    skipped: f64,
    /// SSIM of the first view rendered with skipping and without.
    ssim: Option<f64>,
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
    /// Volume samples taken over all views.
    samples: u64,
}

/// One timed view: index, wall-clock ms, GPU pass ms, samples, image.
struct Timed {
    view: usize,
    ms: f64,
    pass_ms: Option<f64>,
    samples: u64,
    frame: Frame,
}

pub fn run(args: RaycastArgs) -> Result<(), Failure> {
    if args.size == 0 || args.steps == 0 || args.cpu_steps > args.steps {
        return Err(Failure::Usage(format!(
            "need --size > 0, --steps > 0 and --cpu-steps <= --steps (got {}, {}, {})",
            args.size, args.steps, args.cpu_steps
        )));
    }
    FrameDesc::new(glam::UVec2::splat(args.size))
        .validate()
        .map_err(|e| Failure::Usage(format!("--size {}: {e}", args.size)))?;
    let names = args.volume.volume_list("phantom");
    let setup = HmdStereo::protocol(args.size, paper::SPAN_PX);
    let radius = setup.radius.unwrap_or(paper::RADIUS_M);
    let image = UVec2::splat(args.size);
    let cameras = (0..args.steps)
        .map(|i| camera(i, args.steps, &setup, radius, image))
        .collect::<Result<Vec<_>, _>>()?;

    let mut renderers: Vec<(Kind, Renderer)> = Vec::new();
    if !args.no_gpu {
        for &sampling in &args.gpu_sampling {
            let gpu = Renderer::new(Backend::Gpu).map_err(|e| {
                Failure::Runtime(format!("{e} (use --no-gpu to time the CPU alone)"))
            })?;
            let kind = match sampling {
                Sampling::Exact => Kind::Gpu,
                Sampling::Filtered => Kind::GpuFiltered,
            };
            renderers.push((kind, gpu));
        }
    }
    if args.cpu_steps > 0 {
        renderers.push((Kind::Cpu, Renderer::Cpu(CpuRenderer::new())));
        if args.cpu_reference {
            renderers.push((Kind::Reference, Renderer::Cpu(CpuRenderer::reference())));
        }
    }
    let cpu_views: Vec<usize> = (0..args.cpu_steps)
        .map(|i| (i * args.steps / args.cpu_steps.max(1)) as usize)
        .collect();
    let views_of = |kind: Kind| match kind {
        Kind::Gpu | Kind::GpuFiltered => (0..cameras.len()).collect::<Vec<_>>(),
        _ => cpu_views.clone(),
    };
    // The reference runs once per volume and mode, whatever the skipping.
    let per_setting: usize = renderers
        .iter()
        .filter(|(k, _)| *k != Kind::Reference)
        .map(|(k, _)| views_of(*k).len() + 1)
        .sum();
    let reference = if args.cpu_reference {
        cpu_views.len() + 1
    } else {
        0
    };
    let total = names.len() * args.shading.len() * (per_setting * args.skipping.len() + reference);
    let mut progress = Progress::new(total);

    let mut volumes = Vec::new();
    for name in &names {
        let loaded = args.volume.with_volume(name).load()?.with_stored_axes();
        // Longest side such that the bounding sphere has the protocol's radius.
        let (lo, hi) = loaded.bounds();
        let extent = hi - lo;
        let size = extent.max_element() * (2.0 * radius as f32) / extent.length();
        let scene = loaded.placed(at(Vec3::ZERO, size), &protocol_frame(), PROTOCOL_UNITS)?;
        let mut runs = Vec::new();
        // The first view of each (mode, renderer, skipping), to compare.
        let mut first_images: Vec<((String, Kind, bool), Frame)> = Vec::new();
        for shading in &args.shading {
            for (n, &skipping) in args.skipping.iter().enumerate() {
                let settings = RenderSettings {
                    shading: *shading,
                    skipping,
                    ..Default::default()
                };
                let mut results = Results::default();
                for (kind, renderer) in &mut renderers {
                    if *kind == Kind::Reference && n > 0 {
                        continue;
                    }
                    let settings = RenderSettings {
                        skipping: skipping && *kind != Kind::Reference,
                        sampling: if *kind == Kind::GpuFiltered {
                            Sampling::Filtered
                        } else {
                            Sampling::Exact
                        },
                        level_of_detail: if *kind == Kind::GpuFiltered {
                            args.lod
                        } else {
                            0.0
                        },
                        ..settings.clone()
                    };
                    let label = format!(
                        "{} {} {shading} skipping {}",
                        loaded.name,
                        kind.name(),
                        if settings.skipping { "on" } else { "off" }
                    );
                    // One untimed frame first: uploads and pipelines on the
                    // GPU, the f32 copy and the clear bricks on the CPU.
                    renderer
                        .upload(&scene)
                        .map_err(|e| Failure::Runtime(e.to_string()))?;
                    time_view(renderer, 0, &scene, &cameras[0], &settings, image)?;
                    progress.step(&format!("{label} warm-up"));
                    let mut timed = Vec::new();
                    for i in views_of(*kind) {
                        let t = time_view(renderer, i, &scene, &cameras[i], &settings, image)?;
                        progress.step(&format!("{label} view {i} {:.1} ms", t.ms));
                        timed.push(t);
                    }
                    let timings = Some(summary(renderer, &timed, image));
                    if let Some(first) = timed.into_iter().next() {
                        let key = (shading.to_string(), *kind, skipping);
                        first_images.push((key, first.frame));
                    }
                    match kind {
                        Kind::Gpu => results.gpu = timings,
                        Kind::GpuFiltered => results.gpu_filtered = timings,
                        Kind::Cpu => results.cpu = timings,
                        Kind::Reference => results.cpu_reference = timings,
                    }
                }
                let image_of =
                    |k: Kind| first_image(&first_images, &shading.to_string(), k, skipping);
                let filtered_ssim = image_of(Kind::Gpu)
                    .zip(image_of(Kind::GpuFiltered))
                    .and_then(|(a, b)| ssim(a, b).ok());
                runs.push(RaycastRun {
                    filtered_speedup: time_ratio(&results.gpu, &results.gpu_filtered),
                    filtered_ssim,
                    shading: shading.to_string(),
                    skipping,
                    extra_samples_per_sample: shading.extra_samples(),
                    cpu_over_gpu_same_views: speedup(&results, &cpu_views),
                    cpu_speedup_over_reference: time_ratio(&results.cpu_reference, &results.cpu),
                    results,
                });
            }
        }
        volumes.push(VolumeRuns {
            volume: VolumeInfo::of(&loaded.name, &scene),
            skipping: skipping_gains(&runs, &first_images),
            runs,
        });
    }

    let report = RaycastReport {
        benchmark: "raycast",
        machine: Machine::this(),
        image: [args.size, args.size],
        fov_degrees: setup.fov.to_degrees(),
        focal_length_m: setup.focal,
        bounding_radius_m: radius,
        steps: args.steps,
        cpu_views,
        cpu_packets: CpuRenderer::new()
            .packet_level()
            .map_or("none", |l| l.name()),
        volumes,
    };
    write_json(&report, &args.json)?;
    print_report(&report);
    Ok(())
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Gpu,
    GpuFiltered,
    Cpu,
    Reference,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Gpu => "gpu",
            Kind::GpuFiltered => "gpu-filtered",
            Kind::Cpu => "cpu",
            Kind::Reference => "cpu-reference",
        }
    }
}

/// Skipping on against off, per mode and backend, where both ran.
/// The first view's image of `kind` in mode `shading`, with or without
/// skipping.
fn first_image<'a>(
    images: &'a [((String, Kind, bool), Frame)],
    shading: &str,
    kind: Kind,
    skipping: bool,
) -> Option<&'a Frame> {
    images
        .iter()
        .find(|((m, k, s), _)| m == shading && *k == kind && *s == skipping)
        .map(|(_, f)| f)
}

fn skipping_gains(
    runs: &[RaycastRun],
    images: &[((String, Kind, bool), Frame)],
) -> Vec<SkippingGain> {
    let mut gains = Vec::new();
    for on in runs.iter().filter(|r| r.skipping) {
        let Some(off) = runs.iter().find(|r| !r.skipping && r.shading == on.shading) else {
            continue;
        };
        let pairs = [
            (Kind::Gpu, &on.results.gpu, &off.results.gpu),
            (
                Kind::GpuFiltered,
                &on.results.gpu_filtered,
                &off.results.gpu_filtered,
            ),
            (Kind::Cpu, &on.results.cpu, &off.results.cpu),
        ];
        for (kind, a, b) in pairs {
            let (Some(a), Some(b)) = (a, b) else { continue };
            let ssim = first_image(images, &on.shading, kind, true)
                .zip(first_image(images, &on.shading, kind, false))
                .and_then(|(x, y)| ssim(x, y).ok());
            gains.push(SkippingGain {
                ssim,
                shading: on.shading.clone(),
                backend: kind.name(),
                speedup: b.mean_ms / a.mean_ms,
                samples_on: a.samples,
                samples_off: b.samples,
                skipped: 1.0 - a.samples as f64 / b.samples.max(1) as f64,
            });
        }
    }
    gains
}

/// View `i` of `n` around the y axis: the eye at distance h + r from the
/// volume's centre, so the bounding sphere's near point is h away.
pub(super) fn camera(
    i: u32,
    n: u32,
    setup: &HmdStereo,
    radius: f64,
    image: UVec2,
) -> Result<RayGen, Failure> {
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
        frame,
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
        samples,
        ms,
    }
}

/// How many times `slow`'s mean time `fast`'s is, where both ran.
fn time_ratio(slow: &Option<Timings>, fast: &Option<Timings>) -> Option<f64> {
    Some(slow.as_ref()?.mean_ms / fast.as_ref()?.mean_ms)
}

fn speedup(results: &Results, cpu_views: &[usize]) -> Option<f64> {
    let (gpu, cpu) = (results.gpu.as_ref()?, results.cpu.as_ref()?);
    let same = cpu_views.iter().filter_map(|&i| gpu.ms.get(i).copied());
    Some(cpu.mean_ms / mean(same))
}

fn print_report(report: &RaycastReport) {
    println!(
        "raycast at {}x{}, {} views about y ({} on the CPU), machine: {}",
        report.image[0],
        report.image[1],
        report.steps,
        report.cpu_views.len(),
        report.machine.cpu
    );
    println!(
        "{:<16} {:<15} {:<4} {:<13} {:>10} {:>10} {:>10} {:>11} {:>8}",
        "volume",
        "shading",
        "skip",
        "backend",
        "mean ms",
        "pass ms",
        "Msamples",
        "Msamples/s",
        "CPU/GPU"
    );
    for v in &report.volumes {
        for run in &v.runs {
            let rows = [
                ("gpu", &run.results.gpu),
                ("gpu-filtered", &run.results.gpu_filtered),
                ("cpu", &run.results.cpu),
                ("cpu-reference", &run.results.cpu_reference),
            ];
            for (name, r) in rows {
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
                    "{:<16} {:<15} {:<4} {:<13} {:>10.1} {:>10} {:>10.1} {:>11.1} {:>8}",
                    v.volume.name,
                    run.shading,
                    if run.skipping { "on" } else { "off" },
                    name,
                    r.mean_ms,
                    pass,
                    r.samples as f64 / 1e6,
                    r.samples_per_s / 1e6,
                    ratio
                );
            }
            if let Some(x) = run.cpu_speedup_over_reference {
                println!(
                    "{:<16} CPU over the scalar reference: {x:.2}x",
                    v.volume.name
                );
            }
            if let (Some(x), Some(s)) = (run.filtered_speedup, run.filtered_ssim) {
                println!(
                    "{:<16} filtered GPU sampling {x:.2}x the exact path's speed, SSIM {s:.5}",
                    v.volume.name
                );
            }
        }
        for g in &v.skipping {
            println!(
                "{:<16} {} {}: skipping {:.2}x faster, {:.1}% of {:.1} M samples skipped, SSIM {}",
                v.volume.name,
                g.shading,
                g.backend,
                g.speedup,
                100.0 * g.skipped,
                g.samples_off as f64 / 1e6,
                g.ssim.map_or("-".into(), |s| format!("{s:.5}"))
            );
        }
    }
    let adapter = report
        .volumes
        .iter()
        .flat_map(|v| &v.runs)
        .find_map(|run| run.results.gpu.as_ref())
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
