//! `caveray bench surfaces`: a triangle mesh (a volume's isosurface, from
//! `--mesh`) alone and inside its volume, on the GPU and the CPU, by the
//! ray-casting benchmark's protocol views: the CPU's BVH build, the bytes
//! each renderer holds per triangle, the first frame (build, upload and
//! pipelines included), the mean of the frames after it with its primary
//! rays a second, and the GPU's image against the CPU's.

use std::path::PathBuf;
use std::time::Instant;

use anari_library_caveray::render::shapes::ShapeSet;
use anari_library_caveray::render::simd::Level;
use anari_library_caveray::render::stereo::{paper, HmdStereo};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, Backend, CpuRenderer, Frame, FrameDesc, RenderSettings, Renderer,
};
use anari_library_caveray::scene::Scene;
use clap::Args;
use glam::{UVec2, Vec3};
use serde::Serialize;

use super::mean;
use super::raycast::camera;
use crate::progress::Progress;
use crate::report::{write_json, Machine, RendererInfo};
use crate::scene::{at, protocol_frame, VolumeArgs, PROTOCOL_UNITS};
use crate::Failure;

#[derive(Args)]
pub struct SurfacesArgs {
    /// The volume, and with --mesh the isosurface drawn as triangles
    /// (required; --mesh-stride sets the triangle count).
    #[command(flatten)]
    volume: VolumeArgs,
    /// Image width and height in pixels.
    #[arg(long, default_value_t = paper::WIDTH)]
    size: u32,
    /// Views around the mesh, each timed after the first.
    #[arg(long, default_value_t = 4)]
    views: u32,
    /// Skip the GPU.
    #[arg(long)]
    no_gpu: bool,
    /// Skip the CPU.
    #[arg(long)]
    no_cpu: bool,
    /// Where to write the results.
    #[arg(long, default_value = "out/bench/surfaces.json")]
    json: PathBuf,
}

#[derive(Serialize)]
struct SurfacesReport {
    benchmark: &'static str,
    machine: Machine,
    image: [u32; 2],
    volume: String,
    triangles: usize,
    vertices: usize,
    /// The CPU's BVH over the mesh (its wide tree), built on the CPU.
    bvh_build_ms: f64,
    /// What the CPU holds per triangle to trace the mesh: the shape and
    /// its wide tree.
    cpu_bytes_per_triangle: f64,
    /// The GPU's surface buffers per triangle (binary tree, primitives,
    /// shading data).
    gpu_bytes_per_triangle: f64,
    /// The SIMD level the CPU's kernels ran at.
    simd: &'static str,
    runs: Vec<Run>,
    /// The first view of the mesh in its volume, GPU against CPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    gpu_cpu_ssim: Option<f64>,
}

#[derive(Serialize)]
struct Run {
    renderer: RendererInfo,
    /// The mesh alone, then inside its volume.
    mesh: Timing,
    mixed: Timing,
}

#[derive(Serialize)]
struct Timing {
    /// The first frame of the scene: BVH, upload and pipelines included.
    first_ms: f64,
    /// Each later view, and their mean.
    ms: Vec<f64>,
    mean_ms: f64,
    /// Primary rays a second at the mean (one a pixel; shading and
    /// secondary rays not counted).
    rays_per_second: f64,
}

pub fn run(args: SurfacesArgs) -> Result<(), Failure> {
    if args.size == 0 || args.views < 2 {
        return Err(Failure::Usage(format!(
            "need --size > 0 and --views >= 2 (got {}, {})",
            args.size, args.views
        )));
    }
    if !args.volume.has_mesh() {
        return Err(Failure::Usage(
            "give the mesh with --mesh FRACTION (the volume's isosurface there)".into(),
        ));
    }
    let image = UVec2::splat(args.size);
    FrameDesc::new(image)
        .validate()
        .map_err(|e| Failure::Usage(format!("--size {}: {e}", args.size)))?;
    let setup = HmdStereo::protocol(args.size, paper::SPAN_PX);
    let radius = setup.radius.unwrap_or(paper::RADIUS_M);
    let cameras = (0..args.views)
        .map(|i| camera(i, args.views, &setup, radius, image))
        .collect::<Result<Vec<_>, _>>()?;
    let loaded = args.volume.load()?.with_stored_axes();
    let (lo, hi) = loaded.bounds();
    let extent = hi - lo;
    let size = extent.max_element() * (2.0 * radius as f32) / extent.length();
    let mixed = loaded.placed(at(Vec3::ZERO, size), &protocol_frame(), PROTOCOL_UNITS)?;
    let shapes = mixed.shapes().to_vec();
    let mesh = Scene::of_shapes(shapes.clone()).map_err(|e| Failure::Runtime(e.to_string()))?;
    let (triangles, vertices) = shapes
        .first()
        .map_or((0, 0), |s| (s.shape.len(), s.shape.vertices()));
    let runtime = |e: anari_library_caveray::render::RenderError| Failure::Runtime(e.to_string());
    let t = Instant::now();
    let traced = ShapeSet::build(&shapes).map_err(runtime)?;
    let bvh_build_ms = t.elapsed().as_secs_f64() * 1e3;
    let all: usize = shapes.iter().map(|s| s.shape.len()).sum();
    let own: u64 = shapes.iter().map(|s| s.shape.heap_bytes()).sum();
    let cpu_bytes_per_triangle = (own + traced.heap_bytes()) as f64 / all.max(1) as f64;
    drop(traced);
    let packed = ShapeSet::packed(&shapes).map_err(runtime)?;
    let gpu_bytes_per_triangle =
        (16 * (packed.words.len() + packed.shading.len())) as f64 / all.max(1) as f64;
    drop(packed);

    let mut renderers: Vec<Renderer> = Vec::new();
    if !args.no_gpu {
        renderers.push(
            Renderer::new(Backend::Gpu).map_err(|e| {
                Failure::Runtime(format!("{e} (use --no-gpu to time the CPU alone)"))
            })?,
        );
    }
    if !args.no_cpu {
        renderers.push(Renderer::Cpu(CpuRenderer::new()));
    }
    let settings = RenderSettings::default();
    let mut progress = Progress::new(renderers.len() * 2 * cameras.len());
    let mut runs = Vec::new();
    let mut firsts: Vec<Frame> = Vec::new();
    for renderer in &mut renderers {
        let name = match renderer {
            Renderer::Gpu(_) => "gpu",
            Renderer::Cpu(_) => "cpu",
        };
        let mut timing = |scene: &Scene, what: &str, keep: &mut Vec<Frame>| {
            let mut ms = Vec::new();
            for (i, rays) in cameras.iter().enumerate() {
                let t = Instant::now();
                let frame = renderer
                    .render(scene, rays, &settings, &FrameDesc::new(image))
                    .map_err(|e| Failure::Runtime(e.to_string()))?;
                let took = t.elapsed().as_secs_f64() * 1e3;
                progress.step(&format!("{name} {what} view {i} {took:.1} ms"));
                if i == 0 && what == "mixed" {
                    keep.push(frame);
                }
                ms.push(took);
            }
            let first_ms = ms.remove(0);
            let mean_ms = mean(ms.iter().copied());
            Ok::<_, Failure>(Timing {
                first_ms,
                mean_ms,
                ms,
                rays_per_second: f64::from(image.x * image.y) / (mean_ms / 1e3),
            })
        };
        let mesh_timing = timing(&mesh, "mesh", &mut firsts)?;
        let mixed_timing = timing(&mixed, "mixed", &mut firsts)?;
        runs.push(Run {
            renderer: RendererInfo::of(renderer),
            mesh: mesh_timing,
            mixed: mixed_timing,
        });
    }
    let gpu_cpu_ssim = match firsts.as_slice() {
        [g, c] => ssim(g, c).ok(),
        _ => None,
    };
    let report = SurfacesReport {
        benchmark: "surfaces",
        machine: Machine::this(),
        image: image.to_array(),
        volume: loaded.name.clone(),
        triangles,
        vertices,
        bvh_build_ms,
        cpu_bytes_per_triangle,
        gpu_bytes_per_triangle,
        simd: Level::chosen().name(),
        runs,
        gpu_cpu_ssim,
    };
    write_json(&report, &args.json)?;
    println!(
        "{} triangles ({} vertices) of {} at {}x{}: the CPU's BVH built in {:.0} ms ({}), {:.0} bytes a triangle on the CPU, {:.0} on the GPU",
        report.triangles,
        report.vertices,
        report.volume,
        args.size,
        args.size,
        report.bvh_build_ms,
        report.simd,
        report.cpu_bytes_per_triangle,
        report.gpu_bytes_per_triangle
    );
    println!("renderer   first mesh ms   mesh ms   Mrays/s   first mixed ms   mixed ms");
    for (run, renderer) in report.runs.iter().zip(&renderers) {
        let name = match renderer {
            Renderer::Gpu(g) => g.adapter().name.clone(),
            Renderer::Cpu(_) => "cpu".to_string(),
        };
        println!(
            "{name:<10} {:>14.1} {:>9.1} {:>9.2} {:>16.1} {:>10.1}",
            run.mesh.first_ms,
            run.mesh.mean_ms,
            run.mesh.rays_per_second / 1e6,
            run.mixed.first_ms,
            run.mixed.mean_ms
        );
    }
    if let Some(s) = report.gpu_cpu_ssim {
        println!("GPU against CPU, first view in the volume: SSIM {s:.4}");
    }
    println!("written to {}", args.json.display());
    Ok(())
}
