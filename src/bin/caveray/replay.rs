//! `caveray replay`: Buchacher's thesis' evaluation of asynchronous rendering with
//! image warping (its Figure 18). A display refreshes at --hz along a head
//! path while the ray caster renders cells within each refresh's budget;
//! every refresh shows the newest complete image warped to that instant's
//! view, and is compared (DSSIM) with the image a renderer without latency
//! would show. Writes JSON, an SVG trace per view and path, and a strip of
//! frames; prints mean and max per warp mode.

use std::path::{Path, PathBuf};

use anari_library_caveray::cave::{pose_along, Eye, HeadPose, PathKey, Rig, Wall};
use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays, RayGen};
use anari_library_caveray::output::{frame_to_rgba, write_rgba_png, Chart, Series, XAxis};
use anari_library_caveray::render::warp::{
    Refresh, RefreshSummary, Timeline, WarpMode, WarpSettings,
};
use anari_library_caveray::render::{Backend, RenderSettings, Renderer, Shading};
use clap::Args;
use glam::UVec2;
use serde::Serialize;

use crate::cluster::Cluster;
use crate::progress::Progress;
use crate::render::wall_size;
use crate::scene::VolumeArgs;
use crate::Failure;

const DEFAULT_PATHS: &str =
    "cave_configs/head_paths/turn_1s.toml,cave_configs/head_paths/step_1s.toml";
/// The head-mounted view's vertical field of view (degrees), square image.
const HMD_FOV_DEGREES: f64 = 90.0;
/// Frames in a strip.
const STRIP_FRAMES: usize = 6;

#[derive(Args)]
pub struct ReplayArgs {
    /// Rig file: its walls, viewer and volume placement.
    #[arg(long, default_value = "cave_configs/cologne_5wall.toml")]
    config: PathBuf,
    /// Head path files, comma-separated (positions of the neck's pivot).
    #[arg(long, default_value = DEFAULT_PATHS)]
    path: String,
    /// Views, comma-separated: hmd (a 90 degree headset view that turns
    /// with the head) and wall names of the rig.
    #[arg(long, default_value = "hmd,front,left")]
    view: String,
    /// Display refresh rate.
    #[arg(long, default_value_t = 90.0)]
    hz: f64,
    /// Warp modes, comma-separated: none, quad, grid, layers.
    #[arg(long, default_value = "none,quad,grid,layers")]
    warp: String,
    /// Simulate a renderer taking this long per image (ms); without it,
    /// cells take the time they take on this machine's CPU.
    #[arg(long)]
    render_ms: Option<f64>,
    /// Image size as a fraction of the wall resolution (the headset view
    /// takes the first wall's).
    #[arg(long, default_value_t = 0.08)]
    scale: f64,
    /// Cells per axis.
    #[arg(long, default_value_t = 8)]
    cells: u32,
    /// Bias of the cell time predictions (>= 1).
    #[arg(long, default_value_t = 1.2)]
    bias: f64,
    /// Layers per pixel for the layers warp.
    #[arg(long, default_value_t = 4)]
    layers: usize,
    /// Steps of the layers warp's re-march.
    #[arg(long, default_value_t = 96)]
    layer_steps: u32,
    /// Pixels between the grid warp's vertices.
    #[arg(long, default_value_t = 4)]
    grid_spacing: u32,
    /// Milliseconds kept free before each refresh for the warp.
    #[arg(long, default_value_t = 2.0)]
    warp_ms: f64,
    #[command(flatten)]
    volume: VolumeArgs,
    /// gpu, cpu, or auto (a hardware GPU where there is one, else the CPU):
    /// what renders the cells, the ideal frames and the warps.
    #[arg(long, default_value = "auto", value_parser = crate::options::backend())]
    backend: Backend,
    /// none, shadows, ao, shadows+ao or directional:N.
    #[arg(long, default_value = "none", value_parser = crate::options::shading)]
    shading: Shading,
    /// Where the JSON report goes.
    #[arg(long, default_value = "out/replay/replay.json")]
    json: PathBuf,
    /// Folder for the SVG traces and the strips of frames.
    #[arg(long, default_value = "out/replay")]
    out: PathBuf,
}

#[derive(Serialize)]
struct Report {
    config: String,
    volume: String,
    hz: f64,
    render_ms: Option<f64>,
    renderer: String,
    shading: String,
    cells: u32,
    bias: f64,
    layers: usize,
    layer_steps: u32,
    grid_spacing: u32,
    modes: Vec<&'static str>,
    /// Every run, in the order of the paths and views asked for.
    runs: Vec<serde_json::Value>,
    /// Under MPI: each rank's views and its waits at the barrier that
    /// keeps the displays' refreshes in step.
    #[serde(skip_serializing_if = "Option::is_none")]
    cluster: Option<Vec<RankWaits>>,
}

#[derive(Serialize, serde::Deserialize)]
struct RankWaits {
    rank: usize,
    views: Vec<String>,
    /// Displayed frames (barriers) this rank took part in.
    frames: usize,
    barrier_mean_ms: f64,
    barrier_max_ms: f64,
}

#[derive(Clone, Serialize)]
struct Run {
    view: String,
    path: String,
    size: [u32; 2],
    mean_age_ms: f64,
    images: u32,
    modes: Vec<ModeSummary>,
    refreshes: Vec<RefreshSummary>,
}

#[derive(Clone, Serialize)]
struct ModeSummary {
    mode: &'static str,
    mean_dssim: f64,
    max_dssim: f64,
}

/// A view that follows the head: a headset's or a wall's.
enum Display<'a> {
    Hmd,
    Wall(&'a Wall),
}

pub fn run(args: ReplayArgs) -> Result<(), Failure> {
    let usage = |m: String| Failure::Usage(m);
    let runtime = |e: &dyn std::fmt::Display| Failure::Runtime(e.to_string());
    if !(args.scale.is_finite() && args.scale > 0.0 && args.scale <= 4.0) {
        return Err(usage(format!(
            "--scale must be in (0, 4], got {}",
            args.scale
        )));
    }
    let modes: Vec<WarpMode> = split(&args.warp)
        .map(|m| m.parse::<WarpMode>())
        .collect::<Result<_, _>>()
        .map_err(usage)?;
    if modes.is_empty() {
        return Err(usage("--warp names no mode".into()));
    }
    if !(1..=anari_library_caveray::render::warp::MAX_LAYERS).contains(&args.layers) {
        return Err(usage(format!(
            "--layers must be 1 to {}, got {}",
            anari_library_caveray::render::warp::MAX_LAYERS,
            args.layers
        )));
    }
    // The settings every run shares, checked before anything is loaded.
    let probe = Timeline {
        hz: args.hz,
        duration: 1.0,
        size: UVec2::ONE,
        cells: UVec2::splat(args.cells.max(1)),
        bias: args.bias,
        layers: args.layers,
        render_ms: args.render_ms,
        warp_ms: args.warp_ms,
        modes: modes.clone(),
        warp: WarpSettings {
            grid_spacing: args.grid_spacing,
            layer_steps: args.layer_steps,
            ..WarpSettings::new(WarpMode::None, (glam::Vec3::ZERO, glam::Vec3::ONE))
        },
    };
    probe.validate().map_err(|e| usage(e.to_string()))?;
    let rig = Rig::load(&args.config)
        .map_err(|e| usage(e.to_string()))?
        .with_neck_model();
    let displays: Vec<(String, Display)> = split(&args.view)
        .map(|v| match v {
            "hmd" => Ok((v.to_string(), Display::Hmd)),
            name => rig
                .wall(name)
                .map(|w| (w.name.clone(), Display::Wall(w)))
                .ok_or_else(|| {
                    let walls: Vec<&str> = rig.walls.iter().map(|w| w.name.as_str()).collect();
                    usage(format!(
                        "--view {name}: the rig has no such wall (it has {}; or hmd)",
                        walls.join(", ")
                    ))
                }),
        })
        .collect::<Result<_, _>>()?;
    let paths: Vec<(String, Vec<PathKey>)> = split(&args.path)
        .map(|p| {
            let keys = rig
                .load_head_path(Path::new(p))
                .map_err(|e| usage(e.to_string()))?;
            Ok((stem(p), keys))
        })
        .collect::<Result<_, Failure>>()?;
    let loaded = args.volume.load()?;
    let scene = loaded.placed(rig.scene, &rig.viewer.frame, rig.units)?;
    let settings = RenderSettings {
        shading: args.shading,
        ..RenderSettings::default()
    };
    let (mut renderer, why) = Renderer::choose(args.backend).map_err(|e| runtime(&e))?;
    if let Some(why) = why {
        eprintln!("caveray: {why}");
    }
    if let Some(why) = renderer
        .upload_for(args.backend, &scene)
        .map_err(|e| runtime(&e))?
    {
        eprintln!("caveray: {why}");
    }
    let renderer_name = renderer.describe();
    eprintln!("caveray: rendering on {renderer_name}");
    std::fs::create_dir_all(&args.out)
        .map_err(|e| Failure::Runtime(format!("cannot create {}: {e}", args.out.display())))?;
    let hmd_resolution = rig
        .walls
        .first()
        .map_or(UVec2::splat(1024), |w| w.resolution);
    let duration = |keys: &[PathKey]| keys.last().map_or(0.0, |k| k.time);
    // Under mpirun the views are shared out over the ranks, and every
    // displayed frame ends at a barrier (the swap lock); a rank with fewer
    // views keeps the lock through its idle turns.
    let cluster = Cluster::join()?;
    let mine = anari_library_caveray::cluster::assign(displays.len(), cluster.size())
        .swap_remove(cluster.rank());
    let turns = displays.len().div_ceil(cluster.size());
    let refreshes_of = |keys: &[PathKey]| (duration(keys) * args.hz).round() as u64;
    let total: u64 = paths
        .iter()
        .map(|(_, k)| refreshes_of(k) * mine.len() as u64)
        .sum();
    let mut progress = Progress::new(total as usize);
    let mut runs = Vec::new();
    let mut waits: Vec<f64> = Vec::new();
    let mut lock_failed = None;
    let mut swap_lock = |waits: &mut Vec<f64>| {
        let t = std::time::Instant::now();
        if let Err(e) = cluster.barrier() {
            lock_failed.get_or_insert(e);
        }
        waits.push(t.elapsed().as_secs_f64() * 1e3);
    };
    for (path_index, (path_name, keys)) in paths.iter().enumerate() {
        for turn in 0..turns {
            let Some(&view_index) = mine.get(turn) else {
                for _ in 0..refreshes_of(keys) {
                    swap_lock(&mut waits);
                }
                continue;
            };
            let (view_name, display) = &displays[view_index];
            let resolution = match display {
                Display::Hmd => hmd_resolution,
                Display::Wall(w) => w.resolution,
            };
            let size = wall_size(resolution, args.scale);
            let timeline = Timeline {
                duration: duration(keys),
                size,
                warp: WarpSettings {
                    bounds: scene.bounds(),
                    ..probe.warp
                },
                ..probe.clone()
            };
            let view_at = |time: f64| -> Result<RayGen, String> {
                let head = pose_along(keys, time).unwrap_or(rig.viewer.head);
                view(&rig, display, &head, size)
            };
            let mut strip: Vec<Vec<image::RgbaImage>> = vec![Vec::new(); modes.len() + 1];
            let every = ((duration(keys) * args.hz).round() as usize / STRIP_FRAMES).max(1);
            let mut k = 0usize;
            let mut each = |r: &Refresh| {
                k += 1;
                if k.is_multiple_of(every) && strip[0].len() < STRIP_FRAMES {
                    strip[0].push(frame_to_rgba(&r.ideal));
                    for (row, s) in strip[1..].iter_mut().zip(&r.shown) {
                        row.push(frame_to_rgba(&s.frame));
                    }
                }
                let worst = r.summary.dssim.iter().copied().fold(0.0, f64::max);
                progress.step(&format!(
                    "{path_name} {view_name} t={:.3} s age {:.1} ms, worst DSSIM {worst:.4}",
                    r.summary.time, r.summary.age_ms
                ));
                swap_lock(&mut waits);
            };
            let refreshes = timeline
                .run(&mut renderer, &scene, &settings, &view_at, &mut each)
                .map_err(|e| runtime(&format!("{path_name}, {view_name}: {e}")))?;
            let name = format!("{path_name}_{view_name}");
            write_trace(
                &args.out.join(format!("{name}.svg")),
                &name,
                &modes,
                &refreshes,
            )?;
            write_strip(&args.out.join(format!("{name}.png")), &strip)?;
            runs.push((
                (path_index, view_index),
                summarise(view_name, path_name, size, &modes, refreshes),
            ));
        }
    }
    if let Some(e) = lock_failed {
        return Err(e);
    }
    let local: Vec<Run> = runs.iter().map(|(_, r)| r).cloned().collect();
    print_summary(&local);
    let json = |e: serde_json::Error| Failure::Runtime(e.to_string());
    let placed: Vec<((usize, usize), serde_json::Value)> = runs
        .into_iter()
        .map(|(at, r)| serde_json::to_value(r).map(|v| (at, v)))
        .collect::<Result<_, _>>()
        .map_err(json)?;
    let waited = RankWaits {
        rank: cluster.rank(),
        views: mine.iter().map(|&i| displays[i].0.clone()).collect(),
        frames: waits.len(),
        barrier_mean_ms: waits.iter().sum::<f64>() / waits.len().max(1) as f64,
        barrier_max_ms: waits.iter().copied().fold(0.0, f64::max),
    };
    let everyone = cluster.gather_json(&(placed, waited))?;
    if !cluster.is_root() {
        return Ok(());
    }
    let ranks = everyone.len();
    let (mut all, waits): (Vec<_>, Vec<_>) = everyone.into_iter().unzip();
    let mut all: Vec<((usize, usize), serde_json::Value)> = all.drain(..).flatten().collect();
    all.sort_by_key(|(at, _)| *at);
    let report = Report {
        config: args.config.display().to_string(),
        volume: loaded.name.clone(),
        hz: args.hz,
        render_ms: args.render_ms,
        renderer: renderer_name,
        shading: args.shading.to_string(),
        cells: args.cells,
        bias: args.bias,
        layers: args.layers,
        layer_steps: args.layer_steps,
        grid_spacing: args.grid_spacing,
        modes: modes.iter().map(|m| m.name()).collect(),
        runs: all.into_iter().map(|(_, r)| r).collect(),
        cluster: (ranks > 1).then_some(waits),
    };
    crate::report::write_json(&report, &args.json)?;
    println!("wrote {} and {}", args.json.display(), args.out.display());
    Ok(())
}

fn split(list: &str) -> impl Iterator<Item = &str> {
    list.split(',').map(str::trim).filter(|s| !s.is_empty())
}

fn stem(path: &str) -> String {
    Path::new(path)
        .file_stem()
        .map_or_else(|| path.to_string(), |s| s.to_string_lossy().into_owned())
}

/// The rays of `display` for a head at `head`: a headset's pinhole turns
/// with the head; a wall's off-axis view only follows the eye.
fn view(rig: &Rig, display: &Display, head: &HeadPose, size: UVec2) -> Result<RayGen, String> {
    let eye = rig.eye_position(head, Eye::Mono);
    match display {
        Display::Hmd => {
            let f = &rig.viewer.frame;
            let camera = PinholeCamera::new(
                eye,
                head.orientation * f.forward,
                head.orientation * f.up,
                HMD_FOV_DEGREES.to_radians(),
                f64::from(size.x) / f64::from(size.y),
                ImageRegion::FULL,
            )
            .map_err(|e| e.to_string())?;
            Ok(camera.ray_gen(size))
        }
        Display::Wall(wall) => {
            let v = rig.view(wall, Eye::Mono, head).map_err(|e| e.to_string())?;
            Ok(v.camera.ray_gen(size))
        }
    }
}

fn summarise(
    view: &str,
    path: &str,
    size: UVec2,
    modes: &[WarpMode],
    refreshes: Vec<RefreshSummary>,
) -> Run {
    let n = refreshes.len().max(1) as f64;
    let modes = modes
        .iter()
        .enumerate()
        .map(|(i, m)| ModeSummary {
            mode: m.name(),
            mean_dssim: refreshes.iter().map(|r| r.dssim[i]).sum::<f64>() / n,
            max_dssim: refreshes.iter().map(|r| r.dssim[i]).fold(0.0, f64::max),
        })
        .collect();
    // Each new image shows as a drop in age.
    let images = refreshes
        .windows(2)
        .filter(|w| w[1].age_ms < w[0].age_ms)
        .count() as u32;
    Run {
        view: view.to_string(),
        path: path.to_string(),
        size: size.to_array(),
        mean_age_ms: refreshes.iter().map(|r| r.age_ms).sum::<f64>() / n,
        images,
        modes,
        refreshes,
    }
}

fn print_summary(runs: &[Run]) {
    println!(
        "{:<10} {:<8} {:>9} {:>7}  {:<7} {:>11} {:>10}",
        "path", "view", "size", "age ms", "warp", "mean DSSIM", "max DSSIM"
    );
    for r in runs {
        for (i, m) in r.modes.iter().enumerate() {
            let (path, view, size, age) = if i == 0 {
                (
                    r.path.as_str(),
                    r.view.as_str(),
                    format!("{}x{}", r.size[0], r.size[1]),
                    format!("{:.1}", r.mean_age_ms),
                )
            } else {
                ("", "", String::new(), String::new())
            };
            println!(
                "{path:<10} {view:<8} {size:>9} {age:>7}  {:<7} {:>11.5} {:>10.5}",
                m.mode, m.mean_dssim, m.max_dssim
            );
        }
    }
}

fn write_trace(
    path: &Path,
    title: &str,
    modes: &[WarpMode],
    refreshes: &[RefreshSummary],
) -> Result<(), Failure> {
    let series: Vec<Series> = modes
        .iter()
        .enumerate()
        .map(|(i, m)| Series {
            name: m.name().to_string(),
            points: refreshes.iter().map(|r| (r.time, r.dssim[i])).collect(),
        })
        .collect();
    let top = refreshes
        .iter()
        .flat_map(|r| r.dssim.iter().copied())
        .fold(1e-4, f64::max);
    let chart = Chart {
        title,
        x_label: "time (s)",
        y_label: "DSSIM against the ideal frame",
        y_range: (0.0, top * 1.05),
        series: &series,
        x_axis: XAxis::Linear,
    };
    std::fs::write(path, chart.to_svg())
        .map_err(|e| Failure::Runtime(format!("cannot write {}: {e}", path.display())))
}

/// Rows: the ideal frames, then each mode's; columns: refreshes.
fn write_strip(path: &Path, rows: &[Vec<image::RgbaImage>]) -> Result<(), Failure> {
    let Some(first) = rows.first().and_then(|r| r.first()) else {
        return Ok(());
    };
    let (w, h, gap) = (first.width(), first.height(), 4);
    let cols = rows.iter().map(Vec::len).max().unwrap_or(0) as u32;
    let mut sheet = image::RgbaImage::from_pixel(
        cols * (w + gap) + gap,
        rows.len() as u32 * (h + gap) + gap,
        image::Rgba([255, 255, 255, 255]),
    );
    for (r, row) in rows.iter().enumerate() {
        for (c, img) in row.iter().enumerate() {
            let (x, y) = (gap + c as u32 * (w + gap), gap + r as u32 * (h + gap));
            image::imageops::overlay(&mut sheet, img, i64::from(x), i64::from(y));
        }
    }
    write_rgba_png(&sheet, path).map_err(|e| Failure::Runtime(e.to_string()))
}
