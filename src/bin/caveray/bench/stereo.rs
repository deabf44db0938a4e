//! `caveray bench stereo`: Buchacher & Erdt's protocol for single-pass stereo by
//! re-projection (Buchacher & Erdt 2017; docs/reprojection_stereo.md). Per data
//! set and shading level, over a rotation about y: the left eye alone
//! (T_l), the right eye alone (T_r), the left eye with re-projection plus
//! compositing (T_l+r), what a full clear of the layers would cost, the
//! speed-up V = 1 - (T_l+r - T_l) / T_r, and the re-projected right
//! image's DSSIM against the two-pass right image. Times are GPU passes,
//! without uploads or read-back, by the renderer's pass clock (GPU
//! timestamps on hardware adapters; the report says which).

use std::path::{Path, PathBuf};

use anari_library_caveray::geometry::{MatrixCamera, PrimaryRays, RayGen};
use anari_library_caveray::output::{Series, XAxis};
use anari_library_caveray::render::stereo::{
    decide, layer_memory, paper, Bounds, Eyes, HmdStereo, LayerFormat, LayerRequest, Reprojection,
};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    dssim, Frame, FrameDesc, GpuRenderer, RenderSettings, Shading,
};
use anari_library_caveray::scene::Scene;
use clap::Args;
use glam::{UVec2, Vec3};
use serde::Serialize;

use super::charts::{self, heatmap, HEATMAP_FULL_SCALE};
use super::{mean, runtime, GPU};
use crate::options::shading;
use crate::progress::Progress;
use crate::report::{write_json, Adapter, Machine, RendererInfo};
use crate::scene::{at, protocol_frame, Loaded, VolumeArgs, PROTOCOL_UNITS};
use crate::Failure;

/// Buchacher & Erdt's data sets, as named in volumes.toml.
const PAPER_VOLUMES: &str = "cthead,dti,engine,vis_male,bonsai";

#[derive(Args)]
pub struct StereoBenchArgs {
    /// Volumes, comma-separated (names from volumes.toml, phantom[:N], ...).
    /// Default: Buchacher & Erdt's cthead, dti, engine, vis_male, bonsai.
    #[command(flatten)]
    volume: VolumeArgs,
    /// Image width and height in pixels.
    #[arg(long, default_value_t = paper::WIDTH)]
    size: u32,
    /// Re-projection layers; the focal length h is the shortest at which
    /// the 1 m bounding sphere fits them.
    #[arg(long, default_value_t = paper::LAYERS)]
    layers: u32,
    /// Shading levels, comma-separated; Buchacher & Erdt's ladder is none and 1,
    /// 4 and 16 directions (0, 4, 16, 64 extra samples per sample).
    #[arg(
        long,
        default_value = "none,directional:1,directional:4,directional:16",
        value_delimiter = ',',
        value_parser = shading
    )]
    shading: Vec<Shading>,
    /// Views in the 360 degree rotation about y.
    #[arg(long, default_value_t = paper::VIEWS)]
    steps: u32,
    /// Texel format of the layers: rgba16f (Buchacher & Erdt's) or rgba32f.
    #[arg(long, default_value = "rgba16f", value_parser = crate::options::layer_format())]
    layer_format: LayerFormat,
    /// Where to write the results; the plot (SVG) and the DSSIM heat maps
    /// (PNG) go next to it.
    #[arg(long, default_value = "out/bench/stereo.json")]
    json: PathBuf,
}

/// What `caveray bench stereo` writes to its JSON file.
#[derive(Serialize)]
struct StereoReport {
    benchmark: &'static str,
    machine: Machine,
    /// The GPU renderer: adapter, API, driver and pass clock.
    renderer: RendererInfo,
    image: [u32; 2],
    layers: u32,
    layer_format: String,
    layer_bytes: u64,
    fov_degrees: f64,
    eye_distance_m: f64,
    focal_length_m: f64,
    bounding_radius_m: Option<f64>,
    sphere_span_px: f64,
    steps: u32,
    datasets: Vec<Dataset>,
}

#[derive(Serialize)]
struct Dataset {
    name: String,
    dims: [u32; 3],
    runs: Vec<StereoRun>,
    /// The worst view's images and DSSIM map, beside the JSON file.
    heatmap: String,
}

/// Means over the views of one data set and shading level.
#[derive(Serialize)]
struct StereoRun {
    shading: String,
    extra_samples_per_sample: u32,
    t_l_ms: f64,
    t_r_ms: f64,
    t_lr_ms: f64,
    reproject_ms: f64,
    /// The ray caster over the left pixels the re-projection pass casts
    /// (the image and the pixels beyond it the right eye sees): the same
    /// rays and samples, so that `reproject_ms / cast_ms` is the
    /// re-projection pass's cost per sample against the ray caster's.
    cast_ms: f64,
    composite_ms: f64,
    /// The compositing reading every ray of the bounding depth range, as
    /// it would without the summary of which blocks wrote where.
    composite_every_offset_ms: f64,
    clear_ms: f64,
    speedup_v: f64,
    dssim_mean: f64,
    dssim_max: f64,
    views: ViewSeries,
}

/// Each view's numbers, in view order.
#[derive(Serialize)]
struct ViewSeries {
    t_l_ms: Vec<f64>,
    t_r_ms: Vec<f64>,
    reproject_ms: Vec<f64>,
    cast_ms: Vec<f64>,
    composite_ms: Vec<f64>,
    composite_every_offset_ms: Vec<f64>,
    clear_ms: Vec<f64>,
    dssim: Vec<f64>,
}

/// One view's measurements.
struct ViewResult {
    t_l: f64,
    t_r: f64,
    reproject: f64,
    cast: f64,
    composite: f64,
    every_offset: f64,
    clear: f64,
    dssim: f64,
}

pub fn run(args: StereoBenchArgs) -> Result<(), Failure> {
    if args.size < 8 || args.steps == 0 || args.layers < 2 {
        return Err(Failure::Usage(format!(
            "need --size >= 8 (SSIM windows are 8x8), --steps > 0 and --layers >= 2 (got {}, {}, {})",
            args.size, args.steps, args.layers
        )));
    }
    let shadings = &args.shading;
    let names = args.volume.volume_list(PAPER_VOLUMES);
    // Every volume is read before anything is rendered: a bad name should
    // not surface an hour into a run.
    let volumes = names
        .iter()
        .map(|name| {
            args.volume
                .with_volume(name)
                .load()
                .map(Loaded::with_stored_axes)
        })
        .collect::<Result<Vec<_>, _>>()?;
    FrameDesc::new(glam::UVec2::splat(args.size))
        .validate()
        .map_err(|e| Failure::Usage(format!("--size {}: {e}", args.size)))?;
    let setup = HmdStereo::protocol(args.size, f64::from(args.layers - 1));
    let sphere_plan = setup
        .plan_with(args.layers)
        .map_err(|e| Failure::Usage(e.to_string()))?;
    let image = UVec2::splat(args.size);
    let eyes = (0..args.steps)
        .map(|i| {
            let angle = std::f64::consts::TAU * f64::from(i) / f64::from(args.steps);
            setup
                .eyes(angle)
                .map_err(|e| Failure::Runtime(e.to_string()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut gpu = GpuRenderer::new().map_err(|e| {
        Failure::Runtime(format!("{e} (re-projection runs on the GPU renderer only)"))
    })?;
    let figures = args.json.parent().unwrap_or(Path::new(".")).to_path_buf();
    if !figures.as_os_str().is_empty() {
        std::fs::create_dir_all(&figures)
            .map_err(|e| Failure::Runtime(format!("cannot create {}: {e}", figures.display())))?;
    }
    let mut progress = Progress::new(names.len() * shadings.len() * (eyes.len() + 1));

    let mut datasets = Vec::new();
    for (name, loaded) in names.iter().zip(&volumes) {
        let (lo, hi) = loaded.bounds();
        let extent = hi - lo;
        // Longest side such that the bounding sphere has radius 1 m.
        let longest = extent.max_element() * 2.0 / extent.length();
        let scene = loaded.placed(at(Vec3::ZERO, longest), &protocol_frame(), PROTOCOL_UNITS)?;
        gpu.upload(&scene).map_err(runtime)?;
        let layers = LayerRequest {
            count: Some(args.layers),
            format: args.layer_format,
        };
        let plans = eyes
            .iter()
            .map(|(l, r)| {
                let eyes = Eyes {
                    left: Ok(*l),
                    right: Ok(*r),
                    sizes: [image; 2],
                };
                decide(eyes, Bounds::of(&scene), layers, Some(GPU))
                    .map_err(|e| Failure::Runtime(format!("{name}: {e}")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut runs = Vec::new();
        for (level, shading) in shadings.iter().enumerate() {
            let settings = RenderSettings {
                shading: *shading,
                ..Default::default()
            };
            let mut bench = Bench {
                gpu: &mut gpu,
                scene: &scene,
                settings: &settings,
                image,
            };
            // Compiles and warms every pipeline before anything is timed.
            bench.view(&eyes[0], &plans[0])?;
            progress.step(&format!("{name} {shading} warm-up"));
            let mut results = Vec::new();
            let mut worst: Option<(f64, Frame, Frame)> = None;
            for (i, (pair, plan)) in eyes.iter().zip(&plans).enumerate() {
                let (r, frames) = bench.view(pair, plan)?;
                progress.step(&format!(
                    "{name} {shading} view {i}: T_l {:.1} T_r {:.1} T_l+r {:.1} ms, DSSIM {:.4}",
                    r.t_l,
                    r.t_r,
                    r.reproject + r.composite,
                    r.dssim
                ));
                if level == 0 && worst.as_ref().is_none_or(|w| r.dssim > w.0) {
                    worst = Some((r.dssim, frames.0, frames.1));
                }
                results.push(r);
            }
            if let Some((_, two_pass, reprojected)) = worst {
                let file = format!("stereo_{}_dssim.png", file_name(name));
                heatmap(&two_pass, &reprojected, &figures.join(&file))?;
            }
            runs.push(summarise(*shading, &results));
        }
        datasets.push(Dataset {
            name: name.clone(),
            dims: scene.volumes()[0].volume.dims().to_array(),
            runs,
            heatmap: format!("stereo_{}_dssim.png", file_name(name)),
        });
    }

    let report = StereoReport {
        benchmark: "stereo",
        machine: Machine::this(),
        renderer: RendererInfo::Gpu(Adapter::of(&gpu)),
        image: [args.size, args.size],
        layers: args.layers,
        layer_format: args.layer_format.to_string(),
        layer_bytes: layer_memory(UVec2::splat(args.size), args.layers, args.layer_format),
        fov_degrees: setup.fov.to_degrees(),
        eye_distance_m: setup.eye_distance,
        focal_length_m: setup.focal,
        bounding_radius_m: setup.radius,
        sphere_span_px: sphere_plan.span_px,
        steps: args.steps,
        datasets,
    };
    write_json(&report, &args.json)?;
    let plot = args.json.with_extension("svg");
    std::fs::write(&plot, speedup_chart(&report))
        .map_err(|e| Failure::Runtime(format!("cannot write {}: {e}", plot.display())))?;
    print_table(&report);
    println!(
        "wrote {}, {} and the heat maps stereo_<volume>_dssim.png (two-pass | re-projected | DSSIM, white = {HEATMAP_FULL_SCALE}) in {}",
        args.json.display(),
        plot.display(),
        figures.display()
    );
    Ok(())
}

struct Bench<'a> {
    gpu: &'a mut GpuRenderer,
    scene: &'a Scene,
    settings: &'a RenderSettings,
    image: UVec2,
}

impl Bench<'_> {
    /// Both ways of rendering one view; returns the times and the two
    /// right images (two-pass, re-projected).
    fn view(
        &mut self,
        (left, right): &(MatrixCamera, MatrixCamera),
        plan: &Reprojection,
    ) -> Result<(ViewResult, (Frame, Frame)), Failure> {
        let desc = FrameDesc::new(self.image);
        let left_rays = left.ray_gen(self.image);
        self.gpu
            .render(self.scene, &left_rays, self.settings, &desc)
            .map_err(runtime)?;
        let t_l = self.gpu.last_pass_ms();
        let two_pass = self
            .gpu
            .render(self.scene, &right.ray_gen(self.image), self.settings, &desc)
            .map_err(runtime)?;
        let t_r = self.gpu.last_pass_ms();
        let stereo = self
            .gpu
            .render_reprojected(self.scene, &left_rays, plan, self.settings, &desc)
            .map_err(runtime)?;
        let clear = self.gpu.time_layer_clear().map_err(runtime)?;
        let cast = cast_rays(&left_rays, plan);
        self.gpu
            .render(
                self.scene,
                &cast,
                self.settings,
                &FrameDesc::new(plan.plan.cast),
            )
            .map_err(runtime)?;
        let cast = self.gpu.last_pass_ms();
        let (_, every_offset) = self.gpu.composite_every_offset().map_err(runtime)?;
        let dssim = dssim(&stereo.right, &two_pass).map_err(runtime)?;
        Ok((
            ViewResult {
                t_l,
                t_r,
                reproject: stereo.times.left_ms,
                cast,
                composite: stereo.times.composite_ms,
                every_offset,
                clear,
                dssim,
            },
            (two_pass, stereo.right),
        ))
    }
}

/// The left eye's rays over the pixels the re-projection pass casts.
fn cast_rays(left: &RayGen, plan: &Reprojection) -> RayGen {
    let first = plan.plan.first.as_vec2();
    RayGen {
        origin: left.origin + first.x * left.origin_dx + first.y * left.origin_dy,
        direction: left.direction + first.x * left.direction_dx + first.y * left.direction_dy,
        ..*left
    }
}

fn file_name(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

fn summarise(shading: Shading, results: &[ViewResult]) -> StereoRun {
    let all = |f: fn(&ViewResult) -> f64| results.iter().map(f).collect::<Vec<_>>();
    let views = ViewSeries {
        t_l_ms: all(|r| r.t_l),
        t_r_ms: all(|r| r.t_r),
        reproject_ms: all(|r| r.reproject),
        cast_ms: all(|r| r.cast),
        composite_ms: all(|r| r.composite),
        composite_every_offset_ms: all(|r| r.every_offset),
        clear_ms: all(|r| r.clear),
        dssim: all(|r| r.dssim),
    };
    let m = |v: &[f64]| mean(v.iter().copied());
    let (t_l, t_r) = (m(&views.t_l_ms), m(&views.t_r_ms));
    let t_lr = mean(results.iter().map(|r| r.reproject + r.composite));
    StereoRun {
        shading: shading.to_string(),
        extra_samples_per_sample: shading.extra_samples(),
        t_l_ms: t_l,
        t_r_ms: t_r,
        t_lr_ms: t_lr,
        reproject_ms: m(&views.reproject_ms),
        cast_ms: m(&views.cast_ms),
        composite_ms: m(&views.composite_ms),
        composite_every_offset_ms: m(&views.composite_every_offset_ms),
        clear_ms: m(&views.clear_ms),
        speedup_v: 1.0 - (t_lr - t_l) / t_r,
        dssim_mean: m(&views.dssim),
        dssim_max: views.dssim.iter().copied().fold(0.0, f64::max),
        views,
    }
}

/// V in percent against extra samples per sample, a line per data set
/// (Buchacher & Erdt's Figure 10).
fn speedup_chart(report: &StereoReport) -> String {
    let series: Vec<Series> = report
        .datasets
        .iter()
        .map(|d| Series {
            name: d.name.clone(),
            points: d
                .runs
                .iter()
                .map(|r| (f64::from(r.extra_samples_per_sample), 100.0 * r.speedup_v))
                .collect(),
        })
        .collect();
    let title = format!(
        "Re-projection speed-up V, {}x{}, {} layers, {}",
        report.image[0],
        report.image[1],
        report.layers,
        report.renderer.adapter().map_or("", |a| &a.name)
    );
    charts::speedup_chart(
        &title,
        "extra volume samples per sample (shading)",
        &series,
        XAxis::Slots,
    )
}

fn print_table(report: &StereoReport) {
    println!(
        "stereo by re-projection at {}x{}, {} {} layers ({:.0} MiB), h = {:.3} m, {} views about y, on {} (pass times by {})",
        report.image[0],
        report.image[1],
        report.layers,
        report.layer_format,
        report.layer_bytes as f64 / (1024.0 * 1024.0),
        report.focal_length_m,
        report.steps,
        report.renderer.adapter().map_or("", |a| &a.name),
        report
            .renderer
            .adapter()
            .map_or("", |a| a.pass_clock.name())
    );
    println!("(/sample: the re-projection pass against the ray caster over the same left pixels)");
    println!(
        "{:<10} {:<15} {:>7} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>7} {:>8} {:>8}",
        "volume",
        "shading",
        "samples",
        "T_l ms",
        "T_r ms",
        "T_l+r ms",
        "/sample",
        "comp ms",
        "all ms",
        "clear ms",
        "V %",
        "DSSIM",
        "max"
    );
    for d in &report.datasets {
        for r in &d.runs {
            println!(
                "{:<10} {:<15} {:>7} {:>9.1} {:>9.1} {:>9.1} {:>9.2} {:>9.1} {:>9.1} {:>9.1} {:>7.1} {:>8.4} {:>8.4}",
                d.name,
                r.shading,
                r.extra_samples_per_sample,
                r.t_l_ms,
                r.t_r_ms,
                r.t_lr_ms,
                r.reproject_ms / r.cast_ms,
                r.composite_ms,
                r.composite_every_offset_ms,
                r.clear_ms,
                100.0 * r.speedup_v,
                r.dssim_mean,
                r.dssim_max
            );
        }
    }
}
