//! `caveray bench cave-stereo`: single-pass stereo by re-projection on
//! every wall of a CAVE, along a head path (walking, turning, rolling,
//! looking down). Per frame and wall: whether the wall's two eyes could be
//! re-projected (and why not), the pass times of the left eye, the right
//! eye and the re-projection (V = 1 - (T_l+r - T_l) / T_r), the DSSIM
//! of the re-projected right eye against its own pass, and the path the
//! cost planner (`PairCosts`) would take from the times of the paths it
//! took on the wall's earlier frames, with its estimate's error. Writes
//! JSON, two plots over time and the worst wall-frame's DSSIM heat map.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anari_library_caveray::cave::{pose_along, Eye, HeadPose, PathKey, Rig, ScenePlacement, Wall};
use anari_library_caveray::geometry::{MatrixCamera, PrimaryRays};
use anari_library_caveray::output::{Chart, Series, XAxis};
use anari_library_caveray::render::stereo::{
    decide, Bounds, Eyes, LayerFormat, LayerRequest, NotEpipolar, PairCosts, PairPath,
    Reprojection, ReprojectionError, TwoPasses,
};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    dssim, Frame, FrameDesc, GpuRenderer, RenderSettings, Shading,
};
use anari_library_caveray::scene::Scene;
use clap::Args;
use glam::UVec2;
use serde::{Deserialize, Deserializer, Serialize};

use super::charts::{self, heatmap};
use super::{mean, runtime, GPU};
use crate::cluster::Cluster;
use crate::options::{shading, step_factor};
use crate::progress::Progress;
use crate::render::wall_size;
use crate::report::{write_json, Adapter, Machine, RendererInfo};
use crate::scene::VolumeArgs;
use crate::Failure;

#[derive(Args)]
pub struct CaveStereoArgs {
    /// Rig file (TOML).
    #[arg(long, default_value = "cave_configs/cologne_5wall.toml")]
    config: PathBuf,
    /// Head path (TOML: `units` and `[[pose]]` with `t` in seconds, `head`
    /// and `ypr` in degrees). Default: the Cologne walk shipped with caveray.
    #[arg(long, default_value = "cave_configs/head_paths/cologne_walk.toml")]
    path: PathBuf,
    /// Render at this fraction of each wall's resolution.
    #[arg(long, default_value_t = 0.25)]
    scale: f64,
    /// Frames, evenly spaced from the path's first pose to its last.
    #[arg(long, default_value_t = 60)]
    frames: u32,
    /// The volume (default: cthead), placed where the rig's `[scene]` says
    /// unless the --volume-* placement options say otherwise.
    #[command(flatten)]
    volume: VolumeArgs,
    /// none, shadows, ao, shadows+ao or directional:N.
    #[arg(long, default_value = "none", value_parser = shading)]
    shading: Shading,
    /// Step length in units of half the smallest voxel.
    #[arg(long, default_value_t = 1.0, value_parser = step_factor)]
    step_factor: f32,
    /// Texel format of the layers (rgba32f: exact, twice the memory).
    #[arg(long, default_value = "rgba16f", value_parser = crate::options::layer_format())]
    layer_format: LayerFormat,
    /// Time each wall-frame's passes this many times, interleaved, and
    /// keep each one's fastest: a noisy machine's stalls then do not land
    /// on one path.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    fastest_of: u32,
    /// Where to write the results; the plots and the heat map go next to it.
    #[arg(long, default_value = "out/bench/cave_stereo.json")]
    json: PathBuf,
}

/// What `caveray bench cave-stereo` writes to its JSON file.
#[derive(Serialize)]
struct CaveStereoReport {
    benchmark: &'static str,
    machine: Machine,
    renderer: RendererInfo,
    rig: String,
    config: String,
    path: String,
    duration_s: f64,
    frames: u32,
    scale: f64,
    volume: String,
    scene_centre: [f64; 3],
    scene_size: f64,
    shading: String,
    layer_format: String,
    wall_frames: usize,
    /// Wall-frames on which either eye sees some of the volume; the others
    /// show only the background and need no stereo method.
    visible_wall_frames: usize,
    reprojected_wall_frames: usize,
    /// Re-projected among the visible wall-frames.
    reprojected_share: f64,
    /// Over the re-projected wall-frames.
    dssim_mean: f64,
    dssim_max: f64,
    /// 1 - (sum T_l+r - sum T_l) / sum T_r over the re-projected wall-frames.
    speedup_v: f64,
    /// The same with the planner's path's time for T_l+r (T_l + T_r where
    /// it took two passes).
    speedup_v_planned: f64,
    planner: PlannerSummary,
    walls: Vec<WallSummary>,
    /// Why visible wall-frames rendered in two passes, most frequent first.
    fallbacks: Vec<Fallback>,
    timeline: Vec<FrameRecord>,
    /// Under MPI: which walls each rank rendered, and per frame each
    /// rank's render time and barrier wait.
    #[serde(skip_serializing_if = "Option::is_none")]
    cluster: Option<ClusterTimes>,
    dssim_plot: String,
    speedup_plot: String,
    heatmap: Option<String>,
}

#[derive(Serialize)]
struct WallSummary {
    name: String,
    size: [u32; 2],
    wall_frames: usize,
    visible: usize,
    reprojected: usize,
    reprojected_share: f64,
    t_l_ms: f64,
    t_r_ms: f64,
    t_lr_ms: f64,
    speedup_v: f64,
    speedup_v_planned: f64,
    /// Wall-frames the planner gave two passes, and the probes among all.
    planned_two_passes: usize,
    probes: usize,
    dssim_mean: f64,
    dssim_max: f64,
    layers_max: u32,
    /// Share of the re-projected frames whose epipolar lines run along
    /// both rows and columns (an epipole on or near the wall).
    radial_share: f64,
}

/// How the cost planner did over the re-projectable wall-frames.
#[derive(Serialize)]
struct PlannerSummary {
    /// Frames of a pose class on one path before the other is measured again.
    probe_after: u64,
    /// Re-projected frames of a wall after which two passes are measured,
    /// if they never were (the warm-up measures them here).
    first_probe: u64,
    planned_two_passes: usize,
    /// Wall-frames whose path was taken to measure it (the warm-up seeds
    /// both paths of every wall, as a session's first frames would).
    probes: usize,
    /// |measured / expected - 1| of the chosen path, where it had an estimate.
    estimate_error_mean: f64,
    estimate_error_max: f64,
    /// Wall-frames (probes aside) whose chosen path measured dearer than
    /// the other, and the milliseconds that cost in all.
    wrong_choices: usize,
    wrong_choice_ms: f64,
}

#[derive(Serialize)]
struct Fallback {
    reason: String,
    count: usize,
    walls: Vec<String>,
    first_t: f64,
}

#[derive(Serialize)]
struct ClusterTimes {
    ranks: Vec<RankFrames>,
    /// Per frame, the slowest rank's render: the frame's time.
    frame_ms: Vec<f64>,
}

/// One rank's walls and timed frames, as it sends them to rank 0.
#[derive(Serialize, Deserialize)]
struct RankFrames {
    rank: usize,
    walls: Vec<String>,
    /// Per timed frame: its walls' renders, then its wait at the barrier.
    render_ms: Vec<f64>,
    barrier_ms: Vec<f64>,
    /// Its walls' records (sent to rank 0, which merges them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    timeline: Vec<FrameRecord>,
}

/// A wall-frame's path or plan: one of a few fixed names. (A named type,
/// so that serde reads it with `known_name` instead of borrowing it from
/// the input, which it does for fields spelt `&str`.)
type PathName = &'static str;

/// One of the names a wall-frame's path or plan takes, read back.
fn known_name<'de, D: Deserializer<'de>>(d: D) -> Result<PathName, D::Error> {
    let name = String::deserialize(d)?;
    ["reprojected", "two-pass", "not visible"]
        .into_iter()
        .find(|k| *k == name)
        .ok_or_else(|| serde::de::Error::custom(format!("unknown path '{name}'")))
}

#[derive(Serialize, Deserialize)]
struct FrameRecord {
    t: f64,
    head: [f64; 3],
    walls: Vec<WallFrame>,
}

#[derive(Serialize, Deserialize, Clone)]
struct WallFrame {
    wall: String,
    /// reprojected, two-pass or not visible.
    #[serde(deserialize_with = "known_name")]
    path: PathName,
    #[serde(skip_serializing_if = "Option::is_none")]
    reason: Option<String>,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    measured: Option<Measured>,
}

#[derive(Serialize, Deserialize, Clone, Copy)]
struct Measured {
    layers: u32,
    families: u32,
    span_px: f64,
    /// Left pixels the re-projection casts, over the image's: the share
    /// of its left pass spent beyond the image's borders.
    cast_share: f64,
    t_l_ms: f64,
    t_r_ms: f64,
    t_lr_ms: f64,
    /// The compositing's share of T_l+r.
    composite_ms: f64,
    speedup_v: f64,
    dssim: f64,
    /// The planner's path, whether it was a probe, what it expected the
    /// path to take and the relative error of that (measured / expected - 1).
    #[serde(deserialize_with = "known_name")]
    planned: PathName,
    probe: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    expected_ms: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    estimate_error: Option<f64>,
    /// The planned path's time: T_l+r, or T_l + T_r.
    t_planned_ms: f64,
}

impl Measured {
    /// The other path's time measured less than the chosen one's.
    fn wrong_choice_ms(&self) -> f64 {
        let two = self.t_l_ms + self.t_r_ms;
        (self.t_planned_ms - two.min(self.t_lr_ms)).max(0.0)
    }
}

pub fn run(args: CaveStereoArgs) -> Result<(), Failure> {
    if !(args.scale.is_finite() && args.scale > 0.0 && args.scale <= 4.0) {
        return Err(Failure::Usage(format!(
            "--scale must be in (0, 4], got {}",
            args.scale
        )));
    }
    if args.frames == 0 {
        return Err(Failure::Usage("--frames must be at least 1".into()));
    }
    let rig = Rig::load(&args.config).map_err(|e| Failure::Usage(e.to_string()))?;
    let keys = rig
        .load_head_path(&args.path)
        .map_err(|e| Failure::Usage(e.to_string()))?;
    let sizes: Vec<UVec2> = rig
        .walls
        .iter()
        .map(|w| wall_size(w.resolution, args.scale))
        .collect();
    for (wall, size) in rig.walls.iter().zip(&sizes) {
        FrameDesc::new(*size)
            .validate()
            .map_err(|e| Failure::Usage(format!("wall {}: {e}", wall.name)))?;
        if size.min_element() < 8 {
            return Err(Failure::Usage(format!(
                "wall {} is {}x{} at --scale {}: DSSIM needs 8x8 pixels",
                wall.name, size.x, size.y, args.scale
            )));
        }
    }
    let name = args
        .volume
        .volume_list("cthead")
        .into_iter()
        .next()
        .unwrap_or_else(|| "cthead".into());
    let loaded = args.volume.with_volume(&name).load()?;
    let placement = loaded.placement(rig.scene)?;
    let scene = loaded.placed(rig.scene, &rig.viewer.frame, rig.units)?;
    let cluster = Cluster::join()?;
    let mine = anari_library_caveray::cluster::assign(rig.walls.len(), cluster.size())
        .swap_remove(cluster.rank());
    let own: Vec<(&Wall, UVec2)> = mine.iter().map(|&i| (&rig.walls[i], sizes[i])).collect();
    let mut gpu = GpuRenderer::new().map_err(|e| {
        Failure::Runtime(format!("{e} (re-projection runs on the GPU renderer only)"))
    })?;
    gpu.upload(&scene).map_err(runtime)?;
    let figures = args.json.parent().unwrap_or(Path::new(".")).to_path_buf();
    if !figures.as_os_str().is_empty() {
        std::fs::create_dir_all(&figures)
            .map_err(|e| Failure::Runtime(format!("cannot create {}: {e}", figures.display())))?;
    }
    let settings = RenderSettings {
        shading: args.shading,
        step_factor: args.step_factor,
        ..Default::default()
    };
    let (start, end) = (keys[0].time, keys[keys.len() - 1].time);
    let times: Vec<f64> = (0..args.frames)
        .map(|i| match args.frames {
            1 => start,
            n => start + (end - start) * f64::from(i) / f64::from(n - 1),
        })
        .collect();
    let mut bench = Bench {
        rig: &rig,
        gpu: &mut gpu,
        scene: &scene,
        settings: &settings,
        format: args.layer_format,
        worst: None,
        costs: PairCosts::new(),
        phase: Phase::Warming,
        fastest_of: args.fastest_of,
    };
    // Compiles and warms every pipeline and fills every buffer before
    // anything is timed (a first frame's times are a first frame's), then
    // gives the planner both paths' times of every wall, a run of frames
    // each, as the first frames of a session would.
    let first = pose(&keys, start);
    let seeding = std::iter::repeat_n(Phase::Seeding, PairCosts::RUN);
    for phase in std::iter::once(Phase::Warming).chain(seeding) {
        bench.phase = phase;
        for &(wall, size) in &own {
            bench.wall(wall, size, &first)?;
        }
    }
    // The ranks start the timed frames together.
    cluster.barrier()?;
    bench.phase = Phase::Timed;
    let mut progress = Progress::new(times.len());
    let mut timeline = Vec::with_capacity(times.len());
    let (mut render_ms, mut barrier_ms) = (Vec::new(), Vec::new());
    for &t in &times {
        let head = pose(&keys, t);
        let mut walls = Vec::with_capacity(own.len());
        let started = Instant::now();
        for &(wall, size) in &own {
            walls.push(bench.wall(wall, size, &head)?);
        }
        render_ms.push(started.elapsed().as_secs_f64() * 1e3);
        // The swap lock: every rank's walls of this frame are done.
        let waited = Instant::now();
        cluster.barrier()?;
        barrier_ms.push(waited.elapsed().as_secs_f64() * 1e3);
        let done = walls.iter().filter(|w| w.path == "reprojected").count();
        let seen = walls.iter().filter(|w| w.path != "not visible").count();
        progress.step(&format!(
            "t = {t:.2} s: {done} of {seen} walls that see the volume re-projected"
        ));
        timeline.push(FrameRecord {
            t,
            head: head.position.to_array(),
            walls,
        });
    }
    let mut ranks = cluster.gather_json(&RankFrames {
        rank: cluster.rank(),
        walls: own.iter().map(|(w, _)| w.name.clone()).collect(),
        render_ms,
        barrier_ms,
        timeline,
    })?;
    if !cluster.is_root() {
        return Ok(());
    }
    // Every rank's walls of each frame, in the rig's order.
    let mut timeline = std::mem::take(&mut ranks[0].timeline);
    for rank in &mut ranks[1..] {
        for (frame, theirs) in timeline.iter_mut().zip(std::mem::take(&mut rank.timeline)) {
            frame.walls.extend(theirs.walls);
        }
    }
    let order = |name: &str| rig.walls.iter().position(|w| w.name == name);
    for frame in &mut timeline {
        frame.walls.sort_by_key(|w| order(&w.wall));
    }
    let cluster_times = (cluster.size() > 1).then(|| ClusterTimes {
        frame_ms: (0..times.len())
            .map(|i| ranks.iter().map(|r| r.render_ms[i]).fold(0.0, f64::max))
            .collect(),
        ranks,
    });
    let heatmap_file = match bench.worst.take() {
        Some((_, two_pass, reprojected)) => {
            let file = file_name(&args.json, "worst.png");
            heatmap(&two_pass, &reprojected, &figures.join(&file))?;
            Some(file)
        }
        None => None,
    };
    let report = summarise(
        &args,
        (&rig, &placement),
        &sizes,
        &name,
        RendererInfo::Gpu(Adapter::of(&gpu)),
        timeline,
        (cluster_times, heatmap_file),
    );
    write_json(&report, &args.json)?;
    for (file, svg) in [
        (&report.dssim_plot, dssim_chart(&report)),
        (&report.speedup_plot, speedup_chart(&report)),
    ] {
        let path = figures.join(file);
        std::fs::write(&path, svg)
            .map_err(|e| Failure::Runtime(format!("cannot write {}: {e}", path.display())))?;
    }
    print_table(&report);
    println!(
        "wrote {}, {}, {}{} in {}",
        args.json.display(),
        report.dssim_plot,
        report.speedup_plot,
        report.heatmap.as_ref().map_or(String::new(), |h| format!(
            " and {h} (the worst wall-frame: two-pass | re-projected | DSSIM)"
        )),
        figures.display()
    );
    Ok(())
}

fn pose(keys: &[PathKey], t: f64) -> HeadPose {
    // A loaded path has at least one pose.
    pose_along(keys, t).unwrap_or(keys[0].pose)
}

/// `<json stem>_<suffix>`.
fn file_name(json: &Path, suffix: &str) -> String {
    let stem = json.file_stem().map_or_else(
        || "cave_stereo".into(),
        |s| s.to_string_lossy().into_owned(),
    );
    format!("{stem}_{suffix}")
}

struct Bench<'a> {
    rig: &'a Rig,
    gpu: &'a mut GpuRenderer,
    scene: &'a Scene,
    settings: &'a RenderSettings,
    format: LayerFormat,
    /// The highest DSSIM so far: (DSSIM, two-pass right, re-projected right).
    worst: Option<(f64, Frame, Frame)>,
    /// The planner, fed only the times of the paths it chose.
    costs: PairCosts,
    phase: Phase,
    /// Times each pass is timed, the fastest kept.
    fastest_of: u32,
}

/// What a wall-frame's times are for.
#[derive(Clone, Copy, PartialEq)]
enum Phase {
    /// Nothing: pipelines and buffers are being made.
    Warming,
    /// The planner, both paths.
    Seeding,
    /// The report, and the planner the chosen path.
    Timed,
}

impl Bench<'_> {
    /// One wall at one head pose: re-projected if the planner and the
    /// GPU allow it, measured against two passes; else why not.
    fn wall(&mut self, wall: &Wall, size: UVec2, head: &HeadPose) -> Result<WallFrame, Failure> {
        let record = |path, reason: Option<String>, measured| WallFrame {
            wall: wall.name.clone(),
            path,
            reason,
            measured,
        };
        let eyes = |eye| {
            self.rig
                .view(wall, eye, head)
                .and_then(|v| v.matrix_camera())
        };
        let (left, right) = match (eyes(Eye::Left), eyes(Eye::Right)) {
            (Ok(l), Ok(r)) => (l, r),
            (Err(e), _) | (_, Err(e)) => {
                return Ok(record("not visible", Some(e.to_string()), None))
            }
        };
        let eyes = Eyes {
            left: Ok(left),
            right: Ok(right),
            sizes: [size; 2],
        };
        let layers = LayerRequest {
            count: None,
            format: self.format,
        };
        let plan = match decide(eyes, Bounds::of(self.scene), layers, Some(GPU)) {
            Ok(plan) => plan,
            Err(TwoPasses::Plan(ReprojectionError::NotEpipolar(NotEpipolar::Behind))) => {
                return Ok(record("not visible", None, None))
            }
            Err(e) => return Ok(record("two-pass", Some(e.to_string()), None)),
        };
        match self.measure(&left, &right, &plan)? {
            Ok(mut measured) => {
                let view = self.rig.walls.iter().position(|w| w.name == wall.name);
                self.plan(view.unwrap_or(0) as u64, &mut measured);
                Ok(record("reprojected", None, Some(measured)))
            }
            Err(why) => Ok(record("two-pass", Some(why), None)),
        }
    }

    /// The planner's path for the wall-frame, from what it measured on the
    /// wall's earlier frames; then the path's time goes to it.
    fn plan(&mut self, view: u64, m: &mut Measured) {
        let class = m.families;
        let choice = self.costs.choose(view, class);
        let ms = |path| match path {
            PairPath::Reprojected => m.t_lr_ms,
            PairPath::TwoPasses => m.t_l_ms + m.t_r_ms,
        };
        if self.phase == Phase::Warming {
            return;
        }
        let left_ms = m.t_lr_ms - m.composite_ms;
        let record = |costs: &mut PairCosts, path| match path {
            PairPath::Reprojected => costs.record_reprojected(view, class, ms(path), left_ms),
            PairPath::TwoPasses => costs.record_two_passes(view, class, ms(path)),
        };
        if self.phase == Phase::Seeding {
            for path in [PairPath::Reprojected, PairPath::TwoPasses] {
                record(&mut self.costs, path);
            }
            return;
        }
        m.estimate_error = record(&mut self.costs, choice.path);
        m.planned = match choice.path {
            PairPath::Reprojected => "reprojected",
            PairPath::TwoPasses => "two-pass",
        };
        m.probe = choice.probe;
        m.expected_ms = choice.expected_ms();
        m.t_planned_ms = ms(choice.path);
    }

    /// Both ways of rendering the wall; the outer error is a failure of
    /// the benchmark, the inner one a re-projection the GPU refused.
    fn measure(
        &mut self,
        left: &MatrixCamera,
        right: &MatrixCamera,
        plan: &Reprojection,
    ) -> Result<Result<Measured, String>, Failure> {
        let size = plan.size;
        let desc = FrameDesc::new(size);
        let left_rays = left.ray_gen(size);
        let right_rays = right.ray_gen(size);
        let (mut t_l, mut t_r, mut t_lr, mut composite_ms) = (f64::MAX, f64::MAX, f64::MAX, 0.0);
        let mut last = None;
        for _ in 0..self.fastest_of {
            self.gpu
                .render(self.scene, &left_rays, self.settings, &desc)
                .map_err(runtime)?;
            t_l = t_l.min(self.gpu.last_pass_ms());
            let two_pass = self
                .gpu
                .render(self.scene, &right_rays, self.settings, &desc)
                .map_err(runtime)?;
            t_r = t_r.min(self.gpu.last_pass_ms());
            let stereo = match self.gpu.render_reprojected(
                self.scene,
                &left_rays,
                plan,
                self.settings,
                &desc,
            ) {
                Ok(s) => s,
                Err(e) => return Ok(Err(e.to_string())),
            };
            let pair = stereo.times.left_ms + stereo.times.composite_ms;
            if pair < t_lr {
                (t_lr, composite_ms) = (pair, stereo.times.composite_ms);
            }
            last = Some((two_pass, stereo));
        }
        let Some((two_pass, stereo)) = last else {
            return Err(Failure::Runtime(
                "internal: a wall-frame timed no time".into(),
            ));
        };
        let d = dssim(&stereo.right, &two_pass).map_err(runtime)?;
        if self.worst.as_ref().is_none_or(|w| d > w.0) {
            self.worst = Some((d, two_pass, stereo.right));
        }
        let pixels = |s: UVec2| f64::from(s.x) * f64::from(s.y);
        Ok(Ok(Measured {
            layers: plan.layers,
            families: plan.plan.family_count(),
            span_px: plan.plan.span_px,
            cast_share: pixels(plan.plan.cast) / pixels(plan.size),
            t_l_ms: t_l,
            t_r_ms: t_r,
            t_lr_ms: t_lr,
            composite_ms,
            speedup_v: 1.0 - (t_lr - t_l) / t_r,
            dssim: d,
            planned: "reprojected",
            probe: false,
            expected_ms: None,
            estimate_error: None,
            t_planned_ms: t_lr,
        }))
    }
}

/// V over a set of measurements, with `pair` as the pair's time: sums,
/// not a mean of ratios.
fn speedup(m: &[Measured], pair: fn(&Measured) -> f64) -> f64 {
    let sum = |f: &dyn Fn(&Measured) -> f64| m.iter().map(f).sum::<f64>();
    let (l, r, lr) = (sum(&|m| m.t_l_ms), sum(&|m| m.t_r_ms), sum(&|m| pair(m)));
    // Sums of the same terms cancel to a rounding error, not to 0.
    let v = if r > 0.0 { 1.0 - (lr - l) / r } else { 0.0 };
    if v.abs() < 1e-9 {
        0.0
    } else {
        v
    }
}

fn share(part: usize, whole: usize) -> f64 {
    if whole == 0 {
        0.0
    } else {
        part as f64 / whole as f64
    }
}

fn summarise(
    args: &CaveStereoArgs,
    (rig, placement): (&Rig, &ScenePlacement),
    sizes: &[UVec2],
    volume: &str,
    renderer: RendererInfo,
    timeline: Vec<FrameRecord>,
    (cluster, heatmap): (Option<ClusterTimes>, Option<String>),
) -> CaveStereoReport {
    let all: Vec<(f64, &WallFrame)> = timeline
        .iter()
        .flat_map(|f| f.walls.iter().map(move |w| (f.t, w)))
        .collect();
    let measured = |wall: Option<&str>| -> Vec<Measured> {
        all.iter()
            .filter(|(_, w)| wall.is_none_or(|n| w.wall == n))
            .filter_map(|(_, w)| w.measured)
            .collect()
    };
    let visible = |wall: Option<&str>| {
        all.iter()
            .filter(|(_, w)| wall.is_none_or(|n| w.wall == n) && w.path != "not visible")
            .count()
    };
    let walls = rig
        .walls
        .iter()
        .zip(sizes)
        .map(|(wall, size)| {
            let name = Some(wall.name.as_str());
            let m = measured(name);
            let seen = visible(name);
            WallSummary {
                name: wall.name.clone(),
                size: size.to_array(),
                wall_frames: timeline.len(),
                visible: seen,
                reprojected: m.len(),
                reprojected_share: share(m.len(), seen),
                t_l_ms: mean(m.iter().map(|m| m.t_l_ms)),
                t_r_ms: mean(m.iter().map(|m| m.t_r_ms)),
                t_lr_ms: mean(m.iter().map(|m| m.t_lr_ms)),
                speedup_v: speedup(&m, |m| m.t_lr_ms),
                speedup_v_planned: speedup(&m, |m| m.t_planned_ms),
                planned_two_passes: m.iter().filter(|m| m.planned == "two-pass").count(),
                probes: m.iter().filter(|m| m.probe).count(),
                dssim_mean: mean(m.iter().map(|m| m.dssim)),
                dssim_max: m.iter().map(|m| m.dssim).fold(0.0, f64::max),
                layers_max: m.iter().map(|m| m.layers).max().unwrap_or(0),
                radial_share: share(m.iter().filter(|m| m.families == 2).count(), m.len()),
            }
        })
        .collect();
    let mut groups: BTreeMap<String, Fallback> = BTreeMap::new();
    for (t, w) in &all {
        let (Some(reason), "two-pass") = (&w.reason, w.path) else {
            continue;
        };
        // Reasons differ in their numbers only: group by the words.
        let key = reason
            .split(|c: char| c.is_ascii_digit())
            .next()
            .unwrap_or(reason)
            .trim_end()
            .to_string();
        let group = groups.entry(key).or_insert_with(|| Fallback {
            reason: reason.clone(),
            count: 0,
            walls: Vec::new(),
            first_t: *t,
        });
        group.count += 1;
        if !group.walls.contains(&w.wall) {
            group.walls.push(w.wall.clone());
        }
    }
    let mut fallbacks: Vec<Fallback> = groups.into_values().collect();
    fallbacks.sort_by_key(|f| std::cmp::Reverse(f.count));
    let m = measured(None);
    let seen = visible(None);
    let stem = |suffix| file_name(&args.json, suffix);
    CaveStereoReport {
        benchmark: "cave-stereo",
        machine: Machine::this(),
        renderer,
        rig: rig.name.clone(),
        config: args.config.display().to_string(),
        path: args.path.display().to_string(),
        duration_s: timeline.last().map_or(0.0, |f| f.t) - timeline.first().map_or(0.0, |f| f.t),
        frames: args.frames,
        scale: args.scale,
        volume: volume.to_string(),
        scene_centre: placement.centre.to_array(),
        scene_size: placement.size,
        shading: args.shading.to_string(),
        layer_format: args.layer_format.to_string(),
        wall_frames: all.len(),
        visible_wall_frames: seen,
        reprojected_wall_frames: m.len(),
        reprojected_share: share(m.len(), seen),
        dssim_mean: mean(m.iter().map(|m| m.dssim)),
        dssim_max: m.iter().map(|m| m.dssim).fold(0.0, f64::max),
        speedup_v: speedup(&m, |m| m.t_lr_ms),
        speedup_v_planned: speedup(&m, |m| m.t_planned_ms),
        planner: planner_summary(&m),
        walls,
        fallbacks,
        timeline,
        cluster,
        dssim_plot: stem("dssim.svg"),
        speedup_plot: stem("speedup.svg"),
        heatmap,
    }
}

fn planner_summary(m: &[Measured]) -> PlannerSummary {
    let errors: Vec<f64> = m
        .iter()
        .filter_map(|m| m.estimate_error)
        .map(f64::abs)
        .collect();
    let wrong: Vec<f64> = m
        .iter()
        .filter(|m| !m.probe)
        .map(Measured::wrong_choice_ms)
        .filter(|&ms| ms > 0.0)
        .collect();
    PlannerSummary {
        probe_after: PairCosts::PROBE_AFTER,
        first_probe: PairCosts::FIRST_PROBE,
        planned_two_passes: m.iter().filter(|m| m.planned == "two-pass").count(),
        probes: m.iter().filter(|m| m.probe).count(),
        estimate_error_mean: mean(errors.iter().copied()),
        estimate_error_max: errors.iter().copied().fold(0.0, f64::max),
        wrong_choices: wrong.len(),
        wrong_choice_ms: wrong.iter().sum(),
    }
}

/// The x axis of both plots over time.
const TIME_AXIS: &str = "time along the head path [s]";

/// One series per wall of `value` over time, re-projected frames only.
fn per_wall(report: &CaveStereoReport, value: fn(&Measured) -> f64) -> Vec<Series> {
    report
        .walls
        .iter()
        .map(|w| Series {
            name: w.name.clone(),
            points: report
                .timeline
                .iter()
                .filter_map(|f| {
                    f.walls
                        .iter()
                        .find(|x| x.wall == w.name)
                        .and_then(|x| x.measured)
                        .map(|m| (f.t, value(&m)))
                })
                .collect(),
        })
        .collect()
}

fn dssim_chart(report: &CaveStereoReport) -> String {
    let series = per_wall(report, |m| m.dssim);
    let top = (report.dssim_max * 100.0).ceil().max(1.0) / 100.0;
    let title = format!(
        "Re-projected right eye vs two passes, {} ({:.0}% of visible wall-frames re-projected)",
        report.rig,
        100.0 * report.reprojected_share
    );
    Chart {
        title: &title,
        x_label: TIME_AXIS,
        y_label: "DSSIM",
        y_range: (0.0, top),
        series: &series,
        x_axis: XAxis::Linear,
    }
    .to_svg()
}

fn speedup_chart(report: &CaveStereoReport) -> String {
    let series = per_wall(report, |m| 100.0 * m.speedup_v);
    let title = format!(
        "Re-projection speed-up V per wall, {}",
        report.renderer.adapter().map_or("", |a| &a.name)
    );
    charts::speedup_chart(&title, TIME_AXIS, &series, XAxis::Linear)
}

fn print_table(report: &CaveStereoReport) {
    if let Some(c) = &report.cluster {
        println!(
            "{} MPI ranks; a frame took {:.1} ms on average (the slowest rank's walls)",
            c.ranks.len(),
            mean(c.frame_ms.iter().copied())
        );
        for r in &c.ranks {
            println!(
                "  rank {}: {} in {:.1} ms a frame, {:.1} ms at the barrier",
                r.rank,
                r.walls.join(", "),
                mean(r.render_ms.iter().copied()),
                mean(r.barrier_ms.iter().copied())
            );
        }
    }
    println!(
        "stereo by re-projection on {} along {} ({} frames over {:.1} s, scale {}, {}), on {}",
        report.rig,
        report.path,
        report.frames,
        report.duration_s,
        report.scale,
        report.volume,
        report.renderer.adapter().map_or("", |a| &a.name)
    );
    println!(
        "{:<10} {:>9} {:>8} {:>12} {:>7} {:>8} {:>8} {:>8} {:>7} {:>9} {:>8} {:>8}",
        "wall",
        "size",
        "visible",
        "reprojected",
        "radial",
        "T_l ms",
        "T_r ms",
        "T_l+r ms",
        "V %",
        "planned %",
        "DSSIM",
        "max"
    );
    for w in &report.walls {
        println!(
            "{:<10} {:>9} {:>8} {:>7} {:>3.0}% {:>6.0}% {:>8.1} {:>8.1} {:>8.1} {:>7.1} {:>9.1} {:>8.4} {:>8.4}",
            w.name,
            format!("{}x{}", w.size[0], w.size[1]),
            w.visible,
            w.reprojected,
            100.0 * w.reprojected_share,
            100.0 * w.radial_share,
            w.t_l_ms,
            w.t_r_ms,
            w.t_lr_ms,
            100.0 * w.speedup_v,
            100.0 * w.speedup_v_planned,
            w.dssim_mean,
            w.dssim_max
        );
    }
    println!(
        "all: {} of {} visible wall-frames re-projected ({:.1}%), V {:.1}%, DSSIM mean {:.4}, max {:.4}",
        report.reprojected_wall_frames,
        report.visible_wall_frames,
        100.0 * report.reprojected_share,
        100.0 * report.speedup_v,
        report.dssim_mean,
        report.dssim_max
    );
    let p = &report.planner;
    println!(
        "planned (re-projection or two passes by the wall's earlier times): V {:.1}%, {} wall-frames in two passes, {} probes, estimate error {:.1}% mean, {:.1}% max, {} wrong choices ({:.1} ms)",
        100.0 * report.speedup_v_planned,
        p.planned_two_passes,
        p.probes,
        100.0 * p.estimate_error_mean,
        100.0 * p.estimate_error_max,
        p.wrong_choices,
        p.wrong_choice_ms
    );
    for f in &report.fallbacks {
        println!(
            "two passes {} times ({}), first at t = {:.2} s: {}",
            f.count,
            f.walls.join(", "),
            f.first_t,
            f.reason
        );
    }
}
