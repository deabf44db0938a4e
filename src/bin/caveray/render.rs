//! `caveray render`: every wall and eye of a rig to PNGs, contact sheets
//! and a timing table (timings.json, from the same `RenderReport` the
//! printed table reads).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anari_library_caveray::cave::{Eye, Rig, View};
use anari_library_caveray::geometry::RayGen;
use anari_library_caveray::output::{contact_sheet, frame_to_rgba, write_rgba_png, SheetLayout};
use anari_library_caveray::render::stereo::{
    decide, Bounds, Eyes, LayerFormat, LayerRequest, RenderFacts, Reprojection,
};
use anari_library_caveray::render::Progress as ViewProgress;
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{Backend, Frame, FrameDesc, RenderSettings, Renderer};
use anari_library_caveray::scene::Scene;
use clap::{Args, ValueEnum};
use glam::UVec2;
use serde::{Deserialize, Serialize};

use crate::cluster::{Cluster, Share};
use crate::data_parallel::{Bricks, DataParallelReport};
use crate::options::{RenderOptions, Strategy};
use crate::progress::Progress;
use crate::report::{write_json, RendererInfo, VolumeInfo};
use crate::scene::VolumeArgs;
use crate::{Failure, Given, HeadArgs};

#[derive(Args)]
pub struct RenderArgs {
    /// Rig file (TOML), e.g. cave_configs/cologne_5wall.toml.
    #[arg(long)]
    config: PathBuf,
    #[command(flatten)]
    volume: VolumeArgs,
    #[command(flatten)]
    head: HeadArgs,
    #[command(flatten)]
    render: RenderOptions,
    /// Render at this fraction of each wall's resolution.
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    #[command(flatten)]
    stereo: StereoArgs,
    /// Folder for the images and timings.json (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// For a multi-view display: the isosurface's value as a fraction of
    /// the volume's value range.
    #[arg(long, default_value_t = 0.4)]
    iso: f32,
    /// For a multi-view display: trilinear or tricubic.
    #[arg(long, default_value = "trilinear")]
    iso_filter: anari_library_caveray::render::iso::IsoFilter,
    /// Data-parallel: cut the volume into this many bricks, render each
    /// brick's region of every view on its own and composite the partial
    /// images front to back. Under mpirun one brick per rank (N must equal
    /// -np); alone, the bricks in turn.
    #[arg(long)]
    parts: Option<usize>,
}

/// How the two eyes of a wall are rendered.
#[derive(Args)]
pub struct StereoArgs {
    /// two-pass: ray cast each eye. reprojection: ray cast the left eye and
    /// re-project it into the right (GPU only); walls where that does not
    /// apply fall back to two passes, with the reason in the output.
    #[arg(long, value_enum, default_value_t = StereoMethod::TwoPass)]
    pub stereo: StereoMethod,
    /// Re-projection layers (default: as many as each wall needs).
    #[arg(long)]
    pub layers: Option<u32>,
    /// Texel format of the layers (rgba32f: exact, twice the memory).
    #[arg(long, default_value = "rgba16f", value_parser = crate::options::layer_format())]
    pub layer_format: LayerFormat,
}

/// How a wall's two eyes are rendered (`--stereo`): not the camera's
/// ANARI `stereoMode`, which says where each eye goes in a frame.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StereoMethod {
    TwoPass,
    Reprojection,
}

impl StereoMethod {
    fn name(self) -> &'static str {
        match self {
            StereoMethod::TwoPass => "two-pass",
            StereoMethod::Reprojection => "reprojection",
        }
    }
}

/// What `caveray render` writes to timings.json.
#[derive(Serialize)]
pub struct RenderReport {
    pub rig: String,
    pub config: String,
    pub renderer: RendererInfo,
    pub volume: VolumeInfo,
    pub strategy: &'static str,
    pub shading: String,
    pub scale: f64,
    pub stereo: &'static str,
    pub head: HeadInfo,
    pub upload_ms: f64,
    pub total_ms: f64,
    /// What the volumes took on the GPU, where it rendered.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_memory: Option<GpuMemory>,
    /// Under MPI: each rank's walls and times, and the frame's time (the
    /// slowest rank's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cluster: Option<ClusterReport>,
    /// Under --parts: the bricks, and each view's render, compositing
    /// time and bytes sent, per process.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub data_parallel: Option<DataParallelReport>,
    pub views: Vec<ViewRecord>,
    pub contact_sheets: Vec<String>,
}

#[derive(Serialize)]
pub struct HeadInfo {
    pub position: [f64; 3],
    pub orientation_xyzw: [f64; 4],
}

#[derive(Serialize)]
pub struct ClusterReport {
    pub ranks: Vec<RankTimes>,
    /// The frame's time: the slowest rank's render.
    pub frame_ms: f64,
}

#[derive(Serialize)]
pub struct RankTimes {
    pub rank: usize,
    pub walls: Vec<String>,
    pub render_ms: f64,
    pub barrier_ms: f64,
}

/// One wall and eye: rendered, or why not.
#[derive(Serialize, Deserialize)]
pub struct ViewRecord {
    pub wall: String,
    pub eye: String,
    #[serde(flatten)]
    pub outcome: Outcome,
}

#[derive(Serialize, Deserialize)]
#[serde(untagged)]
pub enum Outcome {
    Rendered(Rendered),
    Skipped { error: String },
}

#[derive(Serialize, Deserialize)]
pub struct Rendered {
    pub width: u32,
    pub height: u32,
    /// Two-pass views: the whole render, read-back included. Re-projected
    /// views: the pass (the left eye's writes the layers, the right eye's
    /// composites), by the renderer's pass clock.
    pub ms: f64,
    pub rays_per_s: f64,
    pub samples: u64,
    pub samples_per_s: f64,
    pub file: String,
    /// "two-pass", or "reprojection (N layers)".
    pub path: String,
    /// Why a wall asked to re-project rendered in two passes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fallback: Option<String>,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub layers: Option<LayerRecord>,
}

#[derive(Serialize, Deserialize)]
pub struct LayerRecord {
    pub layers: u32,
    pub layer_format: String,
    pub layer_bytes: u64,
    /// Longest run of right pixels one left ray writes.
    pub span_px: f64,
    /// 1: the epipolar lines are all nearer the rows (or all nearer the
    /// columns); 2: both kinds cross the wall.
    pub families: u32,
    /// Both eyes of the wall, read-back included.
    pub wall_ms: f64,
}

impl Rendered {
    fn new(size: UVec2, ms: f64, samples: u64, file: String, path: String) -> Self {
        let seconds = ms / 1e3;
        Self {
            width: size.x,
            height: size.y,
            ms,
            rays_per_s: f64::from(size.x * size.y) / seconds,
            samples,
            samples_per_s: samples as f64 / seconds,
            file,
            path,
            fallback: None,
            layers: None,
        }
    }
}

/// A wall's image size at `scale` (at least 1 x 1).
/// A wall's image size at `scale` of its resolution, at least 1x1.
pub fn wall_size(resolution: glam::UVec2, scale: f64) -> glam::UVec2 {
    (resolution.as_dvec2() * scale)
        .round()
        .max(glam::DVec2::ONE)
        .as_uvec2()
}

pub fn run(args: RenderArgs, given: &Given) -> Result<(), Failure> {
    if !(args.scale.is_finite() && args.scale > 0.0 && args.scale <= 4.0) {
        return Err(Failure::Usage(format!(
            "--scale must be in (0, 4], got {}",
            args.scale
        )));
    }
    let display = crate::render_display::is_display(&args.config);
    if display {
        given.refuse(
            &[
                "--strategy",
                "--shading",
                "--backend",
                "--step-factor",
                "--gpu-sampling",
                "--stereo",
                "--layers",
                "--layer-format",
                "--head",
                "--head-ypr",
                "--time",
                "--parts",
            ],
            ["does", "do"],
            "not apply to a multi-view display, which renders an isosurface per view on the CPU \
             from the display's own eye line (its options: --iso, --iso-filter, --scale and the \
             volume options)",
        )?;
    } else {
        given.refuse(
            &["--iso", "--iso-filter"],
            ["applies", "apply"],
            "to multi-view displays only, not to a rig",
        )?;
    }
    if args.parts.is_some() && args.stereo.stereo == StereoMethod::Reprojection {
        return Err(Failure::Usage(
            "--parts renders every eye of every wall from its bricks; re-projection stereo \
             needs one renderer to see the whole volume (use --stereo two-pass)"
                .into(),
        ));
    }
    if args.stereo.stereo == StereoMethod::TwoPass {
        given.refuse(
            &["--layers", "--layer-format"],
            ["applies", "apply"],
            "to --stereo reprojection only",
        )?;
    }
    if display {
        return crate::render_display::run(
            &args.config,
            &args.volume,
            args.scale,
            args.iso,
            args.iso_filter,
            &args.out,
        );
    }
    if args.stereo.layers == Some(0) {
        return Err(Failure::Usage(
            "--layers must be at least 1 (or left out to let the planner choose)".into(),
        ));
    }
    let rig = Rig::load(&args.config).map_err(|e| Failure::Usage(e.to_string()))?;
    // Every wall's image must fit before anything is loaded or rendered.
    for wall in &rig.walls {
        FrameDesc::new(wall_size(wall.resolution, args.scale))
            .validate()
            .map_err(|e| Failure::Usage(format!("wall \"{}\": {e}", wall.name)))?;
    }
    let head = args.head.pose(&rig)?;
    let cluster = Cluster::join()?;
    let loaded = args.volume.load()?;
    // A rank of a data-parallel job reads its brick of a grid alone: the
    // value range the transfer function spans comes from every rank's
    // brick. (Every rank reads the whole of a mesh.)
    let range = match (args.parts, loaded.volume.structured()) {
        (Some(n), Some(grid)) if cluster.size() > 1 => {
            Some(crate::data_parallel::value_range(grid, n, &cluster)?)
        }
        _ => None,
    };
    let scene = loaded.placed_in(rig.scene, &rig.viewer.frame, rig.units, range)?;
    let settings = args.render.settings();
    std::fs::create_dir_all(&args.out)
        .map_err(|e| Failure::Runtime(format!("cannot create {}: {e}", args.out.display())))?;
    let bricks = args
        .parts
        .map(|n| Bricks::new(&scene, &settings, n, &cluster))
        .transpose()?;
    // View-parallel: the walls shared out; data-parallel: every rank sees
    // every wall.
    let mine = match bricks {
        Some(_) => (0..rig.walls.len()).collect(),
        None => anari_library_caveray::cluster::assign(rig.walls.len(), cluster.size())
            .swap_remove(cluster.rank()),
    };
    let mut renderer = args.render.renderer()?;

    let start = Instant::now();
    let uploaded = match &bricks {
        Some(b) => b.scenes().next().unwrap_or(&scene),
        None => &scene,
    };
    let fell_back = renderer
        .upload_for(args.render.backend, uploaded)
        .map_err(|e| Failure::Runtime(e.to_string()))?;
    if let Some(why) = fell_back {
        eprintln!("caveray: {why}");
    }
    let upload_ms = start.elapsed().as_secs_f64() * 1e3;

    let views = rig.views(&head);
    let mut progress = Progress::new(
        views
            .iter()
            .filter(|(w, ..)| mine.iter().any(|&i| std::ptr::eq(*w, &rig.walls[i])))
            .count(),
    );
    let mut records = Vec::new();
    let mut images: Vec<(usize, Eye, image::RgbaImage)> = Vec::new();
    let mut costs = Vec::new();
    let job = ViewJob {
        scene: &scene,
        settings: &settings,
        strategy: args.render.strategy,
    };
    for (wall_index, wall) in rig.walls.iter().enumerate() {
        if !mine.contains(&wall_index) {
            continue;
        }
        let size = wall_size(wall.resolution, args.scale);
        let wall_views: Vec<&(_, Eye, _)> = views
            .iter()
            .filter(|(w, _, _)| std::ptr::eq(*w, wall))
            .collect();
        let pair = match args.stereo.stereo {
            StereoMethod::TwoPass => Err("--stereo two-pass".to_string()),
            StereoMethod::Reprojection => stereo_pair(
                &wall_views,
                &renderer,
                &scene,
                &settings,
                size,
                &args.stereo,
            ),
        };
        match pair {
            Ok((left, reprojection)) => {
                let frames = progress.within(2, &wall.name, |counter| {
                    job.reprojected(&mut renderer, &wall.name, left, &reprojection, counter)
                })?;
                for (eye, frame, rendered) in frames {
                    let image = frame_to_rgba(&frame);
                    if cluster.is_root() {
                        write(&image, &args.out.join(&rendered.file))?;
                    }
                    progress.step(&format!(
                        "{}_{} {}x{} {:.1} ms (re-projection, {} layers)",
                        wall.name,
                        eye.name(),
                        size.x,
                        size.y,
                        rendered.ms,
                        reprojection.layers
                    ));
                    images.push((wall_index, eye, image));
                    records.push((
                        wall_index,
                        ViewRecord {
                            wall: wall.name.clone(),
                            eye: eye.name().to_string(),
                            outcome: Outcome::Rendered(rendered),
                        },
                    ));
                }
            }
            Err(reason) => {
                for (_, eye, view) in &wall_views {
                    let label = format!("{}_{}", wall.name, eye.name());
                    let record = |outcome| {
                        (
                            wall_index,
                            ViewRecord {
                                wall: wall.name.clone(),
                                eye: eye.name().to_string(),
                                outcome,
                            },
                        )
                    };
                    let rays = view
                        .as_ref()
                        .map_err(|e| e.to_string())
                        .and_then(|v| args.render.strategy.rays(v, size));
                    let rays = match rays {
                        Ok(r) => r,
                        Err(error) => {
                            progress.step(&format!("{label}: skipped ({error})"));
                            records.push(record(Outcome::Skipped { error }));
                            continue;
                        }
                    };
                    let (frame, mut rendered) = match &bricks {
                        None => progress.within(1, &label, |counter| {
                            job.single(&mut renderer, &label, &rays, size, counter)
                        })?,
                        Some(b) => {
                            let t = Instant::now();
                            let (frame, cost) = progress.within(1, &label, |counter| {
                                b.render_view(&mut renderer, &rays, size, &cluster, counter)
                            })?;
                            costs.push(cost);
                            let Some(frame) = frame else {
                                progress.step(&format!("{label}: bricks sent"));
                                continue;
                            };
                            let rendered = Rendered::new(
                                size,
                                t.elapsed().as_secs_f64() * 1e3,
                                frame.samples,
                                format!("{label}.png"),
                                format!("data-parallel ({} bricks)", b.len()),
                            );
                            (frame, rendered)
                        }
                    };
                    if args.stereo.stereo == StereoMethod::Reprojection && *eye != Eye::Mono {
                        rendered.fallback = Some(reason.clone());
                    }
                    let image = frame_to_rgba(&frame);
                    if cluster.is_root() {
                        write(&image, &args.out.join(&rendered.file))?;
                    }
                    progress.step(&format!(
                        "{label} {}x{} {:.1} ms",
                        size.x, size.y, rendered.ms
                    ));
                    records.push(record(Outcome::Rendered(rendered)));
                    images.push((wall_index, *eye, image));
                }
            }
        }
    }

    let data_parallel = match &bricks {
        Some(_) if !cluster.is_root() => return Ok(()),
        Some(b) => Some(b.report(cluster.size(), costs)),
        None => None,
    };
    // View-parallel: every rank's images and records to rank 0.
    let mut shares = Vec::new();
    if bricks.is_none() {
        let render_ms = start.elapsed().as_secs_f64() * 1e3;
        let waited = Instant::now();
        cluster.barrier()?;
        let share = Share::of(
            cluster.rank(),
            mine.iter().map(|&i| rig.walls[i].name.clone()).collect(),
            (render_ms, waited.elapsed().as_secs_f64() * 1e3),
            &records,
            &images,
        )?;
        shares = cluster.gather(&share)?;
        if !cluster.is_root() {
            return Ok(());
        }
        for other in shares.iter().filter(|s| s.rank != share.rank) {
            for (i, (wall_index, eye, w, h)) in other.images.iter().enumerate() {
                let image = image::RgbaImage::from_raw(*w, *h, other.pixels[i].clone())
                    .ok_or_else(|| {
                        Failure::Runtime(format!("rank {}: a short image", other.rank))
                    })?;
                let eye = Eye::ALL
                    .into_iter()
                    .find(|e| e.name() == eye)
                    .ok_or_else(|| Failure::Runtime(format!("rank {}: eye '{eye}'", other.rank)))?;
                images.push((*wall_index, eye, image));
            }
            for (wall_index, value) in &other.records {
                let record = serde_json::from_value(value.clone())
                    .map_err(|e| Failure::Runtime(format!("rank {}: {e}", other.rank)))?;
                if let ViewRecord {
                    outcome: Outcome::Rendered(r),
                    ..
                } = &record
                {
                    let at = images
                        .iter()
                        .rposition(|(w, e, _)| w == wall_index && e.name() == record.eye);
                    if let Some(at) = at {
                        write(&images[at].2, &args.out.join(&r.file))?;
                    }
                }
                records.push((*wall_index, record));
            }
        }
    }
    // In the rig's wall order, each wall's eyes as rendered.
    records.sort_by_key(|(wall_index, _)| *wall_index);
    let cluster_report = (bricks.is_none() && cluster.size() > 1).then(|| ClusterReport {
        frame_ms: shares.iter().map(|s| s.render_ms).fold(0.0, f64::max),
        ranks: shares
            .iter()
            .map(|s| RankTimes {
                rank: s.rank,
                walls: s.walls.clone(),
                render_ms: s.render_ms,
                barrier_ms: s.barrier_ms,
            })
            .collect(),
    });
    let records: Vec<ViewRecord> = records.into_iter().map(|(_, r)| r).collect();
    let contact_sheets = write_sheets(&rig, &images, &args.out)?;
    let report = RenderReport {
        rig: rig.name.clone(),
        config: args.config.display().to_string(),
        renderer: RendererInfo::of(&renderer),
        volume: VolumeInfo::of(&loaded.name, &scene),
        strategy: args.render.strategy.name(),
        shading: settings.shading.to_string(),
        scale: args.scale,
        stereo: args.stereo.stereo.name(),
        head: HeadInfo {
            position: head.position.to_array(),
            orientation_xyzw: head.orientation.to_array(),
        },
        upload_ms,
        total_ms: start.elapsed().as_secs_f64() * 1e3,
        gpu_memory: GpuMemory::of(&renderer),
        cluster: cluster_report,
        data_parallel,
        views: records,
        contact_sheets,
    };
    write_json(&report, &args.out.join("timings.json"))?;
    print_summary(&report);
    Ok(())
}

/// What every view of one run shares.
struct ViewJob<'a> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
    strategy: Strategy,
}

impl ViewJob<'_> {
    /// One eye, ray cast on its own, counting into `counter`.
    fn single(
        &self,
        renderer: &mut Renderer,
        label: &str,
        rays: &RayGen,
        size: UVec2,
        counter: &ViewProgress,
    ) -> Result<(Frame, Rendered), Failure> {
        let t = Instant::now();
        let frame = renderer
            .render_until(
                self.scene,
                rays,
                self.settings,
                &FrameDesc::new(size),
                counter,
            )
            .map_err(|e| Failure::Runtime(format!("{label}: {e}")))?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let rendered = Rendered::new(
            size,
            ms,
            frame.samples,
            format!("{label}.png"),
            "two-pass".into(),
        );
        Ok((frame, rendered))
    }

    /// Both eyes of a wall from one ray casting pass, counting into
    /// `counter`.
    fn reprojected(
        &self,
        renderer: &mut Renderer,
        wall: &str,
        left: &View,
        reprojection: &Reprojection,
        counter: &ViewProgress,
    ) -> Result<Vec<(Eye, Frame, Rendered)>, Failure> {
        let Renderer::Gpu(gpu) = renderer else {
            return Err(Failure::Runtime(
                "internal: re-projection planned without a GPU".into(),
            ));
        };
        let size = reprojection.size;
        let rays = self
            .strategy
            .rays(left, size)
            .map_err(|e| Failure::Runtime(format!("{wall}: {e}")))?;
        let t = Instant::now();
        let frames = gpu
            .render_reprojected_until(
                self.scene,
                &rays,
                reprojection,
                self.settings,
                &FrameDesc::new(size),
                counter,
            )
            .map_err(|e| Failure::Runtime(format!("{wall}: {e}")))?;
        let wall_ms = t.elapsed().as_secs_f64() * 1e3;
        let rendered = |eye: Eye, ms: f64, samples: u64| Rendered {
            layers: Some(LayerRecord {
                layers: reprojection.layers,
                layer_format: reprojection.format.to_string(),
                layer_bytes: reprojection.memory(),
                span_px: reprojection.plan.span_px,
                families: reprojection.plan.family_count(),
                wall_ms,
            }),
            ..Rendered::new(
                size,
                ms,
                samples,
                format!("{wall}_{}.png", eye.name()),
                format!("reprojection ({} layers)", reprojection.layers),
            )
        };
        let left = rendered(Eye::Left, frames.times.left_ms, frames.left.samples);
        let right = rendered(Eye::Right, frames.times.composite_ms, 0);
        Ok(vec![
            (Eye::Left, frames.left, left),
            (Eye::Right, frames.right, right),
        ])
    }
}

/// A wall's two eyes and their re-projection plan, or why the wall
/// renders in two passes.
fn stereo_pair<'v>(
    views: &[&'v (
        &anari_library_caveray::cave::Wall,
        Eye,
        anari_library_caveray::geometry::Result<View>,
    )],
    renderer: &Renderer,
    scene: &Scene,
    settings: &RenderSettings,
    size: UVec2,
    args: &StereoArgs,
) -> Result<(&'v View, Reprojection), String> {
    let find = |eye: Eye| {
        views
            .iter()
            .find(|(_, e, _)| *e == eye)
            .and_then(|(_, _, v)| v.as_ref().ok())
    };
    let pair = find(Eye::Left).zip(find(Eye::Right));
    let missing = || "the wall does not show a usable left and right eye".to_string();
    let camera = |v: &View| v.matrix_camera().map_err(|e| e.to_string());
    let eyes = Eyes {
        left: pair.ok_or_else(missing).and_then(|(l, _)| camera(l)),
        right: pair.ok_or_else(missing).and_then(|(_, r)| camera(r)),
        sizes: [size; 2],
    };
    let facts = RenderFacts {
        reprojects: renderer.backend() == Backend::Gpu,
        background_image: settings.background_image.is_some(),
        hits: false,
    };
    let layers = LayerRequest {
        count: args.layers,
        format: args.layer_format,
    };
    let reprojection =
        decide(eyes, Bounds::of(scene), layers, Some(facts)).map_err(|e| e.to_string())?;
    // Planned, so both eyes are there.
    let (left, _) = pair.ok_or_else(missing)?;
    Ok((left, reprojection))
}

/// One contact sheet per eye that has any image; returns the file names.
fn write_sheets(
    rig: &Rig,
    images: &[(usize, Eye, image::RgbaImage)],
    out: &Path,
) -> Result<Vec<String>, Failure> {
    let layout = SheetLayout::for_rig(rig);
    let mut files = Vec::new();
    for eye in Eye::ALL {
        let mut cells: Vec<Option<image::RgbaImage>> = vec![None; rig.walls.len()];
        for (i, e, image) in images {
            if *e == eye {
                cells[*i] = Some(image.clone());
            }
        }
        if cells.iter().all(Option::is_none) {
            continue;
        }
        let file = format!("cave_{}.png", eye.name());
        write(&contact_sheet(&layout, &cells), &out.join(&file))?;
        files.push(file);
    }
    Ok(files)
}

fn write(image: &image::RgbaImage, path: &Path) -> Result<(), Failure> {
    write_rgba_png(image, path).map_err(|e| Failure::Runtime(e.to_string()))
}

/// The volumes' textures (or pools and page tables) on the GPU, and
/// whether they were paged within a budget (set, or found from what the
/// driver allocates).
#[derive(Serialize)]
pub struct GpuMemory {
    pub bytes: u64,
    pub paged: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub budget: Option<u64>,
}

impl GpuMemory {
    fn of(renderer: &Renderer) -> Option<Self> {
        let Renderer::Gpu(g) = renderer else {
            return None;
        };
        Some(Self {
            bytes: g.volume_bytes(),
            paged: g.streaming().wanted > 0,
            budget: g.memory_budget(),
        })
    }
}

fn print_summary(report: &RenderReport) {
    println!(
        "{} on {}",
        report.rig,
        report.renderer.adapter().map_or("the CPU", |a| &a.name)
    );
    println!(
        "{:<10} {:<6} {:>11} {:>10} {:>10} {:>12}  path",
        "wall", "eye", "size", "ms", "Mrays/s", "Msamples/s"
    );
    for v in &report.views {
        let (wall, eye) = (&v.wall, &v.eye);
        let r = match &v.outcome {
            Outcome::Skipped { error } => {
                println!("{wall:<10} {eye:<6} skipped: {error}");
                continue;
            }
            Outcome::Rendered(r) => r,
        };
        let path = match &r.fallback {
            Some(why) => format!("two-pass: {why}"),
            None => r.path.clone(),
        };
        println!(
            "{wall:<10} {eye:<6} {:>11} {:>10.1} {:>10.2} {:>12.1}  {path}",
            format!("{}x{}", r.width, r.height),
            r.ms,
            r.rays_per_s / 1e6,
            r.samples_per_s / 1e6
        );
    }
    println!(
        "path: two-pass ray casts each eye on its own; reprojection ray casts the left eye and \
         re-projects it into the right (--stereo reprojection)"
    );
    println!(
        "upload {:.1} ms, total {:.1} ms; images, contact sheets and timings.json are in the output folder",
        report.upload_ms, report.total_ms
    );
    if let Some(c) = &report.cluster {
        println!(
            "{} MPI ranks; the frame took {:.1} ms (the slowest rank's render)",
            c.ranks.len(),
            c.frame_ms
        );
        for r in &c.ranks {
            println!(
                "  rank {}: {} in {:.1} ms, {:.1} ms at the barrier",
                r.rank,
                r.walls.join(", "),
                r.render_ms,
                r.barrier_ms
            );
        }
    }
    if let Some(m) = report.gpu_memory.as_ref().filter(|m| m.paged) {
        let mib = |b: u64| b as f64 / f64::from(1 << 20);
        println!(
            "the volume is paged on the GPU: {:.1} MiB of bricks and page table{}",
            mib(m.bytes),
            m.budget.map_or(String::new(), |b| format!(
                " within a budget of {:.1} MiB",
                mib(b)
            ))
        );
    }
}
