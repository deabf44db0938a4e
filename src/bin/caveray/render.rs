//! `caveray render`: every wall and eye of a rig to PNGs, contact sheets
//! and a timing table.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anari_library_caveray::cave::{Eye, Rig, View};
use anari_library_caveray::geometry::{pinhole_from_matrices, MatrixCamera, PrimaryRays, RayGen};
use anari_library_caveray::output::{contact_sheet, frame_to_rgba, write_rgba_png, SheetLayout};
use anari_library_caveray::render::stereo::{Bounds, LayerFormat, Reprojection};
use anari_library_caveray::render::{Backend, Frame, FrameDesc, RenderSettings, Renderer, Shading};
use anari_library_caveray::scene::Scene;
use clap::{Args, ValueEnum};
use glam::UVec2;
use serde_json::{json, Value};

use crate::progress::Progress;
use crate::scene::VolumeArgs;
use crate::{Failure, HeadArgs};

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
}

/// How the two eyes of a wall are rendered.
#[derive(Args)]
pub struct StereoArgs {
    /// two-pass: ray cast each eye. reprojection: ray cast the left eye and
    /// re-project it into the right (GPU only); walls where that does not
    /// apply fall back to two passes, with the reason in the output.
    #[arg(long, value_enum, default_value_t = StereoMode::TwoPass)]
    pub stereo: StereoMode,
    /// Re-projection layers (default: as many as each wall needs).
    #[arg(long)]
    pub layers: Option<u32>,
    /// Texel format of the layers: rgba16f or rgba32f.
    #[arg(long, default_value = "rgba16f")]
    pub layer_format: LayerFormat,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StereoMode {
    TwoPass,
    Reprojection,
}

/// Renderer choices shared by `render` and `bench`.
#[derive(Args)]
pub struct RenderOptions {
    /// Which camera model turns each view into rays.
    #[arg(long, value_enum, default_value_t = Strategy::Offaxis)]
    pub strategy: Strategy,
    /// none, shadows, ao, shadows+ao or directional:N.
    #[arg(long, default_value = "none", value_parser = shading)]
    pub shading: Shading,
    /// gpu, cpu, or auto (the GPU where there is one, else the CPU reference).
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    pub backend: BackendArg,
    /// Step length in units of half the smallest voxel.
    #[arg(long, default_value_t = 1.0)]
    pub step_factor: f32,
}

fn shading(s: &str) -> Result<Shading, String> {
    s.parse()
        .map_err(|e: anari_library_caveray::render::RenderError| e.to_string())
}

impl RenderOptions {
    pub fn settings(&self) -> RenderSettings {
        RenderSettings {
            shading: self.shading,
            step_factor: self.step_factor,
            ..Default::default()
        }
    }

    /// The chosen renderer, saying so (and why the GPU is missing) on stderr.
    pub fn renderer(&self) -> Result<Renderer, Failure> {
        let renderer = match self.backend {
            BackendArg::Gpu => Renderer::new(Backend::Gpu)
                .map_err(|e| Failure::Runtime(format!("{e} (try --backend cpu)")))?,
            BackendArg::Cpu => {
                Renderer::new(Backend::Cpu).map_err(|e| Failure::Runtime(e.to_string()))?
            }
            BackendArg::Auto => {
                let (renderer, missing) = Renderer::gpu_or_cpu();
                if let Some(e) = missing {
                    eprintln!("caveray: {e}; falling back to the CPU reference renderer");
                }
                renderer
            }
        };
        eprintln!("caveray: rendering on {}", renderer.describe());
        Ok(renderer)
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
    Auto,
    Gpu,
    Cpu,
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

pub fn run(args: RenderArgs) -> Result<(), Failure> {
    if !(args.scale.is_finite() && args.scale > 0.0 && args.scale <= 4.0) {
        return Err(Failure::Usage(format!(
            "--scale must be in (0, 4], got {}",
            args.scale
        )));
    }
    if args.stereo.layers == Some(0) {
        return Err(Failure::Usage(
            "--layers must be at least 1 (or left out to let the planner choose)".into(),
        ));
    }
    let rig = Rig::load(&args.config).map_err(|e| Failure::Usage(e.to_string()))?;
    let head = args.head.pose(&rig)?;
    let loaded = args.volume.load()?;
    let scene = loaded.placed(rig.scene.centre.as_vec3(), rig.scene.size as f32)?;
    let settings = args.render.settings();
    std::fs::create_dir_all(&args.out)
        .map_err(|e| Failure::Runtime(format!("cannot create {}: {e}", args.out.display())))?;
    let mut renderer = args.render.renderer()?;

    let start = Instant::now();
    renderer
        .upload(&scene)
        .map_err(|e| Failure::Runtime(e.to_string()))?;
    let upload_ms = start.elapsed().as_secs_f64() * 1e3;

    let views = rig.views(&head);
    let mut progress = Progress::new(views.len());
    let mut records = Vec::new();
    let mut images: Vec<(usize, Eye, image::RgbaImage)> = Vec::new();
    let job = ViewJob {
        scene: &scene,
        settings: &settings,
        strategy: args.render.strategy,
    };
    for (wall_index, wall) in rig.walls.iter().enumerate() {
        let size = (wall.resolution.as_dvec2() * args.scale)
            .round()
            .max(glam::DVec2::ONE)
            .as_uvec2();
        let wall_views: Vec<&(_, Eye, _)> = views
            .iter()
            .filter(|(w, _, _)| std::ptr::eq(*w, wall))
            .collect();
        let pair = match args.stereo.stereo {
            StereoMode::TwoPass => Err("--stereo two-pass".to_string()),
            StereoMode::Reprojection => {
                stereo_pair(&wall_views, &renderer, &scene, size, &args.stereo)
            }
        };
        let mut done = Vec::new();
        match pair {
            Ok((left, reprojection)) => {
                let (frames, mut wall_records) =
                    job.reprojected(&mut renderer, &wall.name, left, &reprojection)?;
                for ((eye, frame), record) in frames.into_iter().zip(&mut wall_records) {
                    let image = frame_to_rgba(&frame);
                    write(
                        &image,
                        &args.out.join(format!("{}_{}.png", wall.name, eye.name())),
                    )?;
                    progress.step(&format!(
                        "{}_{} {}x{} {:.1} ms (re-projection, {} layers)",
                        wall.name,
                        eye.name(),
                        size.x,
                        size.y,
                        record["ms"].as_f64().unwrap_or(0.0),
                        reprojection.layers
                    ));
                    images.push((wall_index, eye, image));
                    done.push(eye);
                }
                records.append(&mut wall_records);
            }
            Err(reason) => {
                for (_, eye, view) in &wall_views {
                    let label = format!("{}_{}", wall.name, eye.name());
                    let rays = view
                        .as_ref()
                        .map_err(|e| e.to_string())
                        .and_then(|v| args.render.strategy.rays(v, size));
                    let rays = match rays {
                        Ok(r) => r,
                        Err(message) => {
                            progress.step(&format!("{label}: skipped ({message})"));
                            records.push(
                                json!({"wall": wall.name, "eye": eye.name(), "error": message}),
                            );
                            continue;
                        }
                    };
                    let (frame, mut record) = job.single(&mut renderer, &label, &rays, size)?;
                    record["wall"] = json!(wall.name);
                    record["eye"] = json!(eye.name());
                    record["path"] = json!("two-pass");
                    if args.stereo.stereo == StereoMode::Reprojection && *eye != Eye::Mono {
                        record["fallback"] = json!(reason);
                    }
                    let image = frame_to_rgba(&frame);
                    write(&image, &args.out.join(format!("{label}.png")))?;
                    progress.step(&format!(
                        "{label} {}x{} {:.1} ms",
                        size.x,
                        size.y,
                        record["ms"].as_f64().unwrap_or(0.0)
                    ));
                    records.push(record);
                    images.push((wall_index, *eye, image));
                }
            }
        }
    }

    let sheets = write_sheets(&rig, &images, &args.out)?;
    let total_ms = start.elapsed().as_secs_f64() * 1e3;
    let report = json!({
        "rig": rig.name,
        "config": args.config.display().to_string(),
        "renderer": renderer_json(&renderer),
        "volume": {
            "name": loaded.name,
            "dims": scene.volume.dims().to_array(),
        },
        "strategy": args.render.strategy.name(),
        "shading": settings.shading.to_string(),
        "scale": args.scale,
        "stereo": match args.stereo.stereo {
            StereoMode::TwoPass => "two-pass",
            StereoMode::Reprojection => "reprojection",
        },
        "head": {
            "position": head.position.to_array(),
            "orientation_xyzw": head.orientation.to_array(),
        },
        "upload_ms": upload_ms,
        "total_ms": total_ms,
        "views": records,
        "contact_sheets": sheets,
    });
    let path = args.out.join("timings.json");
    let text =
        serde_json::to_string_pretty(&report).map_err(|e| Failure::Runtime(e.to_string()))?;
    std::fs::write(&path, text + "\n")
        .map_err(|e| Failure::Runtime(format!("cannot write {}: {e}", path.display())))?;
    print_summary(&report);
    Ok(())
}

/// Frames of a wall's eyes, and their timing records.
type WallResult = (Vec<(Eye, Frame)>, Vec<Value>);

/// What every view of one run shares.
struct ViewJob<'a> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
    strategy: Strategy,
}

impl ViewJob<'_> {
    /// One eye, ray cast on its own; the record lacks wall and eye.
    fn single(
        &self,
        renderer: &mut Renderer,
        label: &str,
        rays: &RayGen,
        size: UVec2,
    ) -> Result<(Frame, Value), Failure> {
        let t = Instant::now();
        let frame = renderer
            .render(self.scene, rays, self.settings, &FrameDesc::new(size))
            .map_err(|e| Failure::Runtime(format!("{label}: {e}")))?;
        let seconds = t.elapsed().as_secs_f64();
        let record = json!({
            "width": size.x,
            "height": size.y,
            "ms": seconds * 1e3,
            "rays_per_s": f64::from(size.x * size.y) / seconds,
            "samples": frame.samples,
            "samples_per_s": frame.samples as f64 / seconds,
            "file": format!("{label}.png"),
        });
        Ok((frame, record))
    }

    /// Both eyes of a wall from one ray casting pass. The left eye's time
    /// includes writing the layers, the right eye's is the compositing.
    fn reprojected(
        &self,
        renderer: &mut Renderer,
        wall: &str,
        left: &View,
        reprojection: &Reprojection,
    ) -> Result<WallResult, Failure> {
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
            .render_reprojected(
                self.scene,
                &rays,
                reprojection,
                self.settings,
                &FrameDesc::new(size),
            )
            .map_err(|e| Failure::Runtime(format!("{wall}: {e}")))?;
        let wall_ms = t.elapsed().as_secs_f64() * 1e3;
        let path = format!("reprojection ({} layers)", reprojection.layers);
        let record = |eye: Eye, ms: f64, samples: u64| {
            json!({
                "wall": wall,
                "eye": eye.name(),
                "width": size.x,
                "height": size.y,
                "ms": ms,
                "rays_per_s": f64::from(size.x * size.y) / (ms / 1e3),
                "samples": samples,
                "samples_per_s": samples as f64 / (ms / 1e3),
                "file": format!("{wall}_{}.png", eye.name()),
                "path": path,
                "layers": reprojection.layers,
                "layer_format": reprojection.format.to_string(),
                "layer_bytes": reprojection.memory(),
                "offsets_px": [reprojection.plan.near_px, reprojection.plan.far_px],
                "wall_ms": wall_ms,
            })
        };
        let records = vec![
            record(Eye::Left, frames.times.left_ms, frames.left.samples),
            record(Eye::Right, frames.times.composite_ms, 0),
        ];
        Ok((
            vec![(Eye::Left, frames.left), (Eye::Right, frames.right)],
            records,
        ))
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
    size: UVec2,
    args: &StereoArgs,
) -> Result<(&'v View, Reprojection), String> {
    if renderer.backend() != Backend::Gpu {
        return Err("re-projection runs on the GPU renderer only".into());
    }
    let find = |eye: Eye| {
        views
            .iter()
            .find(|(_, e, _)| *e == eye)
            .and_then(|(_, _, v)| v.as_ref().ok())
    };
    let (Some(left), Some(right)) = (find(Eye::Left), find(Eye::Right)) else {
        return Err("the wall does not show a usable left and right eye".into());
    };
    let camera = |v: &View| v.matrix_camera().map_err(|e| e.to_string());
    let reprojection = Reprojection::new(
        &camera(left)?,
        &camera(right)?,
        size,
        Bounds::of(scene),
        args.layers,
        args.layer_format,
    )
    .map_err(|e| e.to_string())?;
    Ok((left, reprojection))
}

pub fn renderer_json(renderer: &Renderer) -> Value {
    match renderer {
        Renderer::Gpu(g) => {
            let info = g.adapter();
            json!({
                "backend": "gpu",
                "adapter": info.name,
                "api": format!("{:?}", info.backend),
                "driver": format!("{} {}", info.driver, info.driver_info),
                "device_type": format!("{:?}", info.device_type),
            })
        }
        Renderer::Cpu(_) => json!({
            "backend": "cpu",
            "threads": rayon::current_num_threads(),
        }),
    }
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

fn print_summary(report: &Value) {
    println!(
        "{} on {}",
        report["rig"].as_str().unwrap_or(""),
        report["renderer"]["adapter"]
            .as_str()
            .unwrap_or("the CPU reference")
    );
    println!(
        "{:<10} {:<6} {:>11} {:>10} {:>10} {:>12}  path",
        "wall", "eye", "size", "ms", "Mrays/s", "Msamples/s"
    );
    for v in report["views"].as_array().into_iter().flatten() {
        let (wall, eye) = (
            v["wall"].as_str().unwrap_or(""),
            v["eye"].as_str().unwrap_or(""),
        );
        if let Some(err) = v["error"].as_str() {
            println!("{wall:<10} {eye:<6} skipped: {err}");
            continue;
        }
        let f = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
        let path = match (v["path"].as_str(), v["fallback"].as_str()) {
            (_, Some(why)) => format!("two-pass: {why}"),
            (Some(p), None) => p.to_string(),
            (None, None) => String::new(),
        };
        println!(
            "{wall:<10} {eye:<6} {:>11} {:>10.1} {:>10.2} {:>12.1}  {path}",
            format!("{}x{}", v["width"], v["height"]),
            f("ms"),
            f("rays_per_s") / 1e6,
            f("samples_per_s") / 1e6
        );
    }
    println!(
        "upload {:.1} ms, total {:.1} ms; images, contact sheets and timings.json are in the output folder",
        report["upload_ms"].as_f64().unwrap_or(0.0),
        report["total_ms"].as_f64().unwrap_or(0.0)
    );
}
