//! `caveray bench`: speed measurements that write JSON and print a summary.
//! Timings are wall-clock per frame, read-back included, after a warm-up
//! frame; compare them only as ratios taken in one run.

use std::path::PathBuf;
use std::time::Instant;

use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays};
use anari_library_caveray::render::{Backend, FrameDesc, RenderSettings, Renderer, Shading};
use anari_library_caveray::scene::Scene;
use clap::{Args, Subcommand};
use glam::{DVec3, UVec2, Vec3};
use serde_json::{json, Value};

use crate::progress::Progress;
use crate::render::renderer_json;
use crate::scene::VolumeArgs;
use crate::Failure;

#[derive(Subcommand)]
pub enum BenchCommand {
    /// The paper's ray-casting setup: 768^2, 110 degree field of view,
    /// volume scaled to a 1 m bounding radius, 360 degrees about y.
    Raycast(RaycastArgs),
    /// Single-pass stereo by re-projection against rendering both eyes,
    /// by the paper's protocol (writes JSON, an SVG plot and heat maps).
    Stereo(crate::bench_stereo::StereoBenchArgs),
}

#[derive(Args)]
pub struct RaycastArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    /// Image width and height in pixels.
    #[arg(long, default_value_t = 768)]
    size: u32,
    /// Shading modes to sweep, comma-separated (none, shadows, ao,
    /// shadows+ao, directional:N).
    #[arg(long, default_value = "none", value_delimiter = ',')]
    shading: Vec<String>,
    /// Views in the 360 degree rotation.
    #[arg(long, default_value_t = 50)]
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

/// The paper's HMD setup (docs/reprojection_stereo.md).
const FOV_DEGREES: f64 = 110.0;
const EYE_DISTANCE_M: f64 = 0.065;
const RADIUS_M: f64 = 1.0;
/// Largest re-projected pixel span, which fixes the focal length h.
const MAX_PIXEL_SPAN: f64 = 32.0;

/// Focal length that keeps the right eye's pixel span at `d_p`:
/// `h = -r + sqrt(r^2 + e r w / (d_p tan a))`.
fn focal_length(width: u32) -> f64 {
    let tan_a = (0.5 * FOV_DEGREES).to_radians().tan();
    let (r, e, w) = (RADIUS_M, EYE_DISTANCE_M, f64::from(width));
    -r + (r * r + e * r * w / (MAX_PIXEL_SPAN * tan_a)).sqrt()
}

pub fn run(command: BenchCommand) -> Result<(), Failure> {
    match command {
        BenchCommand::Raycast(args) => raycast(args),
        BenchCommand::Stereo(args) => crate::bench_stereo::run(args),
    }
}

fn raycast(args: RaycastArgs) -> Result<(), Failure> {
    if args.size == 0 || args.steps == 0 || args.cpu_steps > args.steps {
        return Err(Failure::Usage(format!(
            "need --size > 0, --steps > 0 and --cpu-steps <= --steps (got {}, {}, {})",
            args.size, args.steps, args.cpu_steps
        )));
    }
    let shadings = parse_shadings(&args.shading)?;
    let loaded = args.volume.load()?;
    // Longest side such that the bounding sphere has radius 1 m.
    let (lo, hi) = loaded.volume.bounds();
    let extent = hi - lo;
    let size = extent.max_element() * (2.0 * RADIUS_M as f32) / extent.length();
    let scene = loaded.placed(Vec3::ZERO, size)?;
    let h = focal_length(args.size);
    let image = UVec2::splat(args.size);
    let cameras = (0..args.steps)
        .map(|i| camera(i, args.steps, h, image))
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
    let total: usize = renderers
        .iter()
        .map(|r| match r.backend() {
            Backend::Gpu => cameras.len() + 1,
            Backend::Cpu => cpu_views.len(),
        })
        .sum::<usize>()
        * shadings.len();
    let mut progress = Progress::new(total);

    let mut runs = Vec::new();
    for shading in &shadings {
        let settings = RenderSettings {
            shading: *shading,
            ..Default::default()
        };
        let mut by_backend = serde_json::Map::new();
        for renderer in &mut renderers {
            let (name, views) = match renderer.backend() {
                Backend::Gpu => ("gpu", (0..cameras.len()).collect::<Vec<_>>()),
                Backend::Cpu => ("cpu", cpu_views.clone()),
            };
            if renderer.backend() == Backend::Gpu {
                renderer
                    .upload(&scene)
                    .map_err(|e| Failure::Runtime(e.to_string()))?;
                time_view(renderer, &scene, &cameras[0], &settings, image)?;
                progress.step(&format!("{name} {shading} warm-up"));
            }
            let mut frames = Vec::new();
            for &i in &views {
                let (ms, samples) = time_view(renderer, &scene, &cameras[i], &settings, image)?;
                progress.step(&format!("{name} {shading} view {i} {ms:.1} ms"));
                frames.push((i, ms, samples));
            }
            by_backend.insert(name.into(), summary(renderer, &frames, image));
        }
        let ratio = speedup(&by_backend, &cpu_views);
        runs.push(json!({
            "shading": shading.to_string(),
            "extra_samples_per_sample": shading.extra_samples(),
            "results": by_backend,
            "cpu_over_gpu_same_views": ratio,
        }));
    }

    let report = json!({
        "benchmark": "raycast",
        "machine": machine(),
        "volume": {"name": loaded.name, "dims": scene.volume.dims().to_array()},
        "image": [args.size, args.size],
        "fov_degrees": FOV_DEGREES,
        "focal_length_m": h,
        "bounding_radius_m": RADIUS_M,
        "steps": args.steps,
        "cpu_views": cpu_views,
        "runs": runs,
    });
    let text =
        serde_json::to_string_pretty(&report).map_err(|e| Failure::Runtime(e.to_string()))?;
    std::fs::write(&args.json, text + "\n")
        .map_err(|e| Failure::Runtime(format!("cannot write {}: {e}", args.json.display())))?;
    print_raycast(&report);
    Ok(())
}

/// View `i` of `n` around the y axis: the eye at distance h + r from the
/// volume's centre, so the bounding sphere's near point is h away.
fn camera(
    i: u32,
    n: u32,
    h: f64,
    image: UVec2,
) -> Result<anari_library_caveray::geometry::RayGen, Failure> {
    let angle = std::f64::consts::TAU * f64::from(i) / f64::from(n);
    let position = (h + RADIUS_M) * DVec3::new(angle.sin(), 0.0, angle.cos());
    PinholeCamera::new(
        position,
        -position,
        DVec3::Y,
        FOV_DEGREES.to_radians(),
        1.0,
        ImageRegion::FULL,
    )
    .map(|c| c.ray_gen(image))
    .map_err(|e| Failure::Runtime(e.to_string()))
}

fn time_view(
    renderer: &mut Renderer,
    scene: &Scene,
    rays: &anari_library_caveray::geometry::RayGen,
    settings: &RenderSettings,
    size: UVec2,
) -> Result<(f64, u64), Failure> {
    let t = Instant::now();
    let frame = renderer
        .render(scene, rays, settings, &FrameDesc::new(size))
        .map_err(|e| Failure::Runtime(e.to_string()))?;
    Ok((t.elapsed().as_secs_f64() * 1e3, frame.samples))
}

fn summary(renderer: &Renderer, frames: &[(usize, f64, u64)], size: UVec2) -> Value {
    let ms: Vec<f64> = frames.iter().map(|f| f.1).collect();
    let total_s = ms.iter().sum::<f64>() / 1e3;
    let samples: u64 = frames.iter().map(|f| f.2).sum();
    json!({
        "renderer": renderer_json(renderer),
        "views": frames.iter().map(|f| f.0).collect::<Vec<_>>(),
        "ms": ms,
        "mean_ms": ms.iter().sum::<f64>() / ms.len() as f64,
        "min_ms": ms.iter().copied().fold(f64::INFINITY, f64::min),
        "rays_per_s": f64::from(size.x * size.y) * frames.len() as f64 / total_s,
        "samples_per_s": samples as f64 / total_s,
    })
}

/// Mean CPU time over mean GPU time on the views both rendered.
fn speedup(results: &serde_json::Map<String, Value>, cpu_views: &[usize]) -> Value {
    let (Some(gpu), Some(cpu)) = (results.get("gpu"), results.get("cpu")) else {
        return Value::Null;
    };
    let gpu_ms = gpu["ms"].as_array().cloned().unwrap_or_default();
    let same: Vec<f64> = cpu_views
        .iter()
        .filter_map(|&i| gpu_ms.get(i).and_then(Value::as_f64))
        .collect();
    let gpu_mean = same.iter().sum::<f64>() / same.len() as f64;
    json!(cpu["mean_ms"].as_f64().unwrap_or(f64::NAN) / gpu_mean)
}

/// `--shading` values, each checked.
pub fn parse_shadings(values: &[String]) -> Result<Vec<Shading>, Failure> {
    values
        .iter()
        .map(|s| {
            s.parse()
                .map_err(|e: anari_library_caveray::render::RenderError| {
                    Failure::Usage(e.to_string())
                })
        })
        .collect()
}

pub fn machine() -> Value {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    json!({
        "cpu": cpu,
        "threads": std::thread::available_parallelism().map_or(1, |n| n.get()),
    })
}

fn print_raycast(report: &Value) {
    println!(
        "raycast {} at {}x{}, {} views about y ({} on the CPU), machine: {}",
        report["volume"]["name"].as_str().unwrap_or(""),
        report["image"][0],
        report["image"][1],
        report["steps"],
        report["cpu_views"].as_array().map_or(0, Vec::len),
        report["machine"]["cpu"].as_str().unwrap_or("")
    );
    println!(
        "{:<15} {:<8} {:>10} {:>10} {:>12} {:>10}",
        "shading", "backend", "mean ms", "min ms", "Msamples/s", "CPU/GPU"
    );
    for run in report["runs"].as_array().into_iter().flatten() {
        for name in ["gpu", "cpu"] {
            let r = &run["results"][name];
            if r.is_null() {
                continue;
            }
            let ratio = if name == "cpu" {
                run["cpu_over_gpu_same_views"]
                    .as_f64()
                    .map_or(String::new(), |x| format!("{x:.2}"))
            } else {
                String::new()
            };
            println!(
                "{:<15} {:<8} {:>10.1} {:>10.1} {:>12.1} {:>10}",
                run["shading"].as_str().unwrap_or(""),
                name,
                r["mean_ms"].as_f64().unwrap_or(f64::NAN),
                r["min_ms"].as_f64().unwrap_or(f64::NAN),
                r["samples_per_s"].as_f64().unwrap_or(f64::NAN) / 1e6,
                ratio
            );
        }
    }
    for run in report["runs"].as_array().into_iter().flatten().take(1) {
        if let Some(r) = run["results"]["gpu"]["renderer"]["adapter"].as_str() {
            println!(
                "GPU adapter: {r} ({})",
                run["results"]["gpu"]["renderer"]["api"]
                    .as_str()
                    .unwrap_or("")
            );
        }
    }
}
