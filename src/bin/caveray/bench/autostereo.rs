//! `caveray bench autostereo`: a multi-view display's image, each subpixel
//! from its own eye, made naively (every view rendered, then interleaved)
//! and per subpixel (one ray a subpixel, the geometric + spectral passes,
//! and the geometric pass with green's hit shaded for red and blue), for
//! several view counts and volumes' isosurfaces. Writes one
//! JSON row per volume and view count: CPU wall clock with the field
//! evaluations counted, or with `--backend gpu` the GPU's pass clock. The
//! times are frame times: the field's f32 copy and crossing box, and each
//! panel's views of its subpixels, are made before the clock starts, as a
//! device makes them once.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anari_library_caveray::cave::{MultiViewDisplay, ViewPattern};
use anari_library_caveray::render::iso::{
    interleave, render_display_by, subpixels_differing, values, Caster, IsoFilter, IsoSettings,
    MultiViewMethod, Panel,
};
use anari_library_caveray::render::{FrameDesc, GpuRenderer};
use clap::Args;
use glam::{UVec2, Vec3};
use serde::Serialize;

use super::runtime;
use crate::report::{write_json, Adapter, Machine, RendererInfo};
use crate::scene::{at, panel_frame, VolumeArgs};
use crate::Failure;

#[derive(Args)]
pub struct AutostereoArgs {
    /// The display file (`views = N` at its top).
    #[arg(long, default_value = "cave_configs/lenticular_8view.toml")]
    config: PathBuf,
    /// Volumes, comma-separated (names from volumes.toml, phantom[:N], ...).
    #[command(flatten)]
    volume: VolumeArgs,
    /// View counts, comma-separated; the lens is rescaled so that each view
    /// keeps its share of a lens.
    #[arg(long, default_value = "1,8,24", value_delimiter = ',')]
    views: Vec<u32>,
    /// The panel's resolution times this.
    #[arg(long, default_value_t = 0.1)]
    scale: f64,
    /// The iso-value as a fraction of each volume's value range.
    #[arg(long, default_value_t = 0.4)]
    iso: f32,
    /// trilinear or tricubic.
    #[arg(long, default_value = "trilinear")]
    filter: IsoFilter,
    /// cpu (wall clock, field evaluations counted) or gpu (the GPU's pass
    /// clock; the naive image is one cast a view, interleaved).
    #[arg(long, default_value = "cpu", value_parser = ["cpu", "gpu"])]
    backend: String,
    /// Times each image this many times and keeps the median (the machine
    /// is shared and noisy).
    #[arg(long, default_value_t = 3)]
    repeat: u32,
    /// Where to write the results.
    #[arg(long, default_value = "out/bench/autostereo.json")]
    json: PathBuf,
}

#[derive(Serialize)]
struct Report {
    benchmark: &'static str,
    machine: Machine,
    display: String,
    resolution: [u32; 2],
    filter: &'static str,
    /// "cpu" (wall clock) or the GPU's adapter and pass clock.
    timed_on: String,
    renderer: RendererInfo,
    /// Each time is the median of this many.
    repeat: u32,
    rows: Vec<Row>,
}

#[derive(Serialize)]
struct Row {
    volume: String,
    views: u32,
    naive_ms: f64,
    per_pixel_ms: f64,
    geometric_spectral_ms: f64,
    green_geometry_ms: f64,
    /// Field evaluations, in units of one view's image (CPU only).
    naive_views: Option<f64>,
    per_pixel_views: Option<f64>,
    geometric_spectral_views: Option<f64>,
    green_geometry_views: Option<f64>,
    /// Share of subpixels the geometric + spectral image has off the naive
    /// one by more than 2 of 255.
    geometric_spectral_differing: f64,
    /// The same for green's hit shaded for red and blue.
    green_geometry_differing: f64,
}

/// The middle of `times` (the upper middle of an even count).
fn median(mut times: Vec<f64>) -> f64 {
    times.sort_by(f64::total_cmp);
    times.get(times.len() / 2).copied().unwrap_or(f64::NAN)
}

pub fn run(args: AutostereoArgs) -> Result<(), Failure> {
    let usage = |m: String| Failure::Usage(m);
    if !(1..=100).contains(&args.repeat) {
        return Err(usage(format!(
            "--repeat must be 1 to 100, got {}",
            args.repeat
        )));
    }
    let base = MultiViewDisplay::load(&args.config).map_err(|e| usage(e.to_string()))?;
    if !(args.scale.is_finite() && args.scale > 0.0 && args.scale <= 1.0) {
        return Err(usage(format!(
            "--scale must be in (0, 1], got {}",
            args.scale
        )));
    }
    if !(args.iso.is_finite() && (0.0..=1.0).contains(&args.iso)) {
        return Err(usage(format!(
            "--iso must be a fraction from 0 to 1, got {}",
            args.iso
        )));
    }
    let resolution = (base.resolution.as_dvec2() * args.scale)
        .round()
        .max(glam::DVec2::ONE)
        .as_uvec2();
    let displays: Vec<MultiViewDisplay> = args
        .views
        .iter()
        .map(|&v| with_views(&base, v, resolution))
        .collect::<Result<_, _>>()
        .map_err(usage)?;
    let mut gpu = match args.backend.as_str() {
        "gpu" => Some(
            GpuRenderer::new().map_err(|e| Failure::Runtime(format!("{e} (try --backend cpu)")))?,
        ),
        _ => None,
    };
    let timed_on = match &gpu {
        Some(g) => format!("GPU {} ({})", g.adapter().name, g.pass_clock().name()),
        None => "cpu".to_string(),
    };
    let renderer = match &gpu {
        Some(g) => RendererInfo::Gpu(Adapter::of(g)),
        None => RendererInfo::Cpu {
            threads: rayon::current_num_threads(),
        },
    };
    let mut rows = Vec::new();
    println!(
        "{:<12} {:>5} {:>10} {:>10} {:>10} {:>10}  {:>8} {:>8} {:>8} {:>8}  {:>8} {:>8}",
        "volume",
        "views",
        "naive ms",
        "per-px ms",
        "g+s ms",
        "green ms",
        "naive",
        "per-px",
        "g+s",
        "green",
        "g+s off",
        "green off"
    );
    for spec in args.volume.volume_list("cthead,engine") {
        let loaded = args.volume.with_volume(&spec).load()?.with_stored_axes();
        // Behind the panel, a third of its width across.
        let panel = &base.screen;
        let size = (panel.width() / 3.0) as f32;
        let centre = panel.centre() - panel.normal() * panel.width() / 3.0;
        let scene = loaded.placed(at(centre.as_vec3(), size), &panel_frame(panel), base.units)?;
        let placed = &scene.volumes()[0];
        let (lo, hi) = placed.volume.value_range();
        let settings = IsoSettings {
            filter: args.filter,
            light: Some(Vec3::new(0.3, 0.5, 1.0)),
            ..IsoSettings::new(lo + args.iso * (hi - lo))
        };
        // What a device keeps from frame to frame (the field as f32, where
        // it can cross the iso-value; each panel's views of its
        // subpixels) is made here, outside the times.
        settings.validate().map_err(runtime)?;
        let field = values(placed).map_err(runtime)?;
        let caster = Caster::new(placed, &field, &settings);
        for d in &displays {
            let panel = Panel::new(
                d.resolution,
                Default::default(),
                d.view_rays().map_err(runtime)?,
                |x, y, c| d.view_of(x, y, c),
            )
            .map_err(runtime)?;
            let row = match gpu.as_mut() {
                None => {
                    let time = |method| -> Result<_, Failure> {
                        let mut times = Vec::new();
                        let mut last = None;
                        for _ in 0..args.repeat {
                            let start = Instant::now();
                            let made =
                                render_display_by(&caster, &panel, method).map_err(runtime)?;
                            times.push(start.elapsed().as_secs_f64() * 1e3);
                            last = Some(made);
                        }
                        let (frame, evals) = last.ok_or_else(|| runtime("no repeat"))?;
                        Ok((frame, evals, median(times)))
                    };
                    let (naive, naive_evals, naive_ms) = time(MultiViewMethod::Naive)?;
                    let (_, per_evals, per_ms) = time(MultiViewMethod::PerSubpixel)?;
                    let (gs, gs_evals, gs_ms) = time(MultiViewMethod::GeometricSpectral)?;
                    let (green, green_evals, green_ms) = time(MultiViewMethod::GreenGeometry)?;
                    let one = naive_evals as f64 / f64::from(d.views);
                    Row {
                        volume: loaded.name.clone(),
                        views: d.views,
                        naive_ms,
                        per_pixel_ms: per_ms,
                        geometric_spectral_ms: gs_ms,
                        green_geometry_ms: green_ms,
                        naive_views: Some(naive_evals as f64 / one),
                        per_pixel_views: Some(per_evals as f64 / one),
                        geometric_spectral_views: Some(gs_evals as f64 / one),
                        green_geometry_views: Some(green_evals as f64 / one),
                        geometric_spectral_differing: subpixels_differing(&gs, &naive, 2),
                        green_geometry_differing: subpixels_differing(&green, &naive, 2),
                    }
                }
                Some(g) => {
                    // Naive: one cast a view, then each subpixel from its
                    // view's image.
                    let desc = FrameDesc::new(d.resolution);
                    let mut naive_times = Vec::new();
                    let mut views = Vec::new();
                    for _ in 0..args.repeat {
                        let mut naive_ms = 0.0;
                        views.clear();
                        for rays in &panel.views {
                            views.push(
                                g.cast_iso(placed, rays, &desc, &settings, &AtomicBool::new(false))
                                    .map_err(runtime)?,
                            );
                            naive_ms += g.last_pass_ms();
                        }
                        naive_times.push(naive_ms);
                    }
                    let naive_ms = median(naive_times);
                    let naive = interleave(&views, &panel).map_err(runtime)?;
                    let method = |g: &mut GpuRenderer, m| -> Result<_, Failure> {
                        let mut times = Vec::new();
                        let mut frame = None;
                        for _ in 0..args.repeat {
                            frame = Some(
                                g.cast_display(
                                    placed,
                                    &panel,
                                    &settings,
                                    m,
                                    &AtomicBool::new(false),
                                )
                                .map_err(runtime)?,
                            );
                            times.push(g.last_pass_ms());
                        }
                        let frame = frame.ok_or_else(|| runtime("no repeat"))?;
                        Ok((frame, median(times)))
                    };
                    let (_, per_ms) = method(g, MultiViewMethod::PerSubpixel)?;
                    let (gs, gs_ms) = method(g, MultiViewMethod::GeometricSpectral)?;
                    let (green, green_ms) = method(g, MultiViewMethod::GreenGeometry)?;
                    Row {
                        volume: loaded.name.clone(),
                        views: d.views,
                        naive_ms,
                        per_pixel_ms: per_ms,
                        geometric_spectral_ms: gs_ms,
                        green_geometry_ms: green_ms,
                        naive_views: None,
                        per_pixel_views: None,
                        geometric_spectral_views: None,
                        green_geometry_views: None,
                        geometric_spectral_differing: subpixels_differing(&gs, &naive, 2),
                        green_geometry_differing: subpixels_differing(&green, &naive, 2),
                    }
                }
            };
            let evals = |v: Option<f64>| v.map_or_else(|| "-".into(), |v| format!("{v:.2}"));
            println!(
                "{:<12} {:>5} {:>10.1} {:>10.1} {:>10.1} {:>10.1}  {:>8} {:>8} {:>8} {:>8}  {:>7.3}% {:>7.3}%",
                row.volume,
                row.views,
                row.naive_ms,
                row.per_pixel_ms,
                row.geometric_spectral_ms,
                row.green_geometry_ms,
                evals(row.naive_views),
                evals(row.per_pixel_views),
                evals(row.geometric_spectral_views),
                evals(row.green_geometry_views),
                100.0 * row.geometric_spectral_differing,
                100.0 * row.green_geometry_differing
            );
            rows.push(row);
        }
    }
    let report = Report {
        benchmark: "autostereo",
        machine: Machine::this(),
        display: base.name.clone(),
        resolution: resolution.to_array(),
        filter: args.filter.name(),
        timed_on,
        renderer,
        repeat: args.repeat,
        rows,
    };
    write_json(&report, &args.json)?;
    println!("wrote {}", args.json.display());
    Ok(())
}

/// `base` with `views` views over `resolution` pixels; the lens is
/// rescaled so that every view keeps the same share of a lens.
fn with_views(
    base: &MultiViewDisplay,
    views: u32,
    resolution: UVec2,
) -> Result<MultiViewDisplay, String> {
    if !(1..=anari_library_caveray::cave::MAX_VIEWS).contains(&views) {
        return Err(format!(
            "--views must be 1 to {}, got {views}",
            anari_library_caveray::cave::MAX_VIEWS
        ));
    }
    let pattern = match &base.pattern {
        ViewPattern::Lens {
            pitch,
            slant,
            offset,
        } => ViewPattern::Lens {
            pitch: pitch * f64::from(views) / f64::from(base.views),
            slant: *slant,
            offset: *offset,
        },
        ViewPattern::Table { .. } if views == base.views => base.pattern.clone(),
        ViewPattern::Table { .. } => {
            return Err(format!(
                "{} gives its views as a table of {}: other view counts need a [lens] display",
                base.name, base.views
            ))
        }
    };
    Ok(MultiViewDisplay {
        views,
        resolution,
        pattern,
        ..base.clone()
    })
}
