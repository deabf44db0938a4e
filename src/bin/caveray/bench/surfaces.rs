//! `caveray bench surfaces`: a triangle mesh alone and inside its volume
//! (a volume's isosurface, from `--mesh`), or the C mesh benchmark's
//! million-triangle scene (`--bumpy`), on the GPU and the CPU: the CPU's
//! BVH build, the bytes each renderer holds per triangle, the first frame
//! (build, upload and pipelines included), the mean of the frames after
//! it with its primary rays a second, and the GPU's image against the
//! CPU's.

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

use super::raycast::camera;
use super::{bumpy, mean};
use crate::progress::Progress;
use crate::report::{write_json, Machine, RendererInfo};
use crate::scene::{at, protocol_frame, VolumeArgs, PROTOCOL_UNITS};
use crate::Failure;

#[derive(Args)]
pub struct SurfacesArgs {
    /// The volume, and with --mesh the isosurface drawn as triangles
    /// (required unless --bumpy; --mesh-stride sets the triangle count).
    #[command(flatten)]
    volume: VolumeArgs,
    /// Instead of an isosurface, the scene of examples/c/mesh_bench.c (a
    /// bumpy sphere of 1 001 112 triangles coloured per vertex, 1 024
    /// spheres around it, seen from 3.5 away with a 60 degree field of
    /// view): what docs/benchmarks.md compares ANARI devices on.
    #[arg(long, conflicts_with = "mesh")]
    bumpy: bool,
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
    /// The first view of the mesh in its volume (of the bumpy scene with
    /// --bumpy), GPU against CPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    gpu_cpu_ssim: Option<f64>,
}

#[derive(Serialize)]
struct Run {
    renderer: RendererInfo,
    /// On the CPU: whether camera rays went to their first surface in
    /// packets of eight neighbours or one by one.
    #[serde(skip_serializing_if = "Option::is_none")]
    camera_rays: Option<&'static str>,
    /// The mesh alone, then inside its volume (not with --bumpy).
    mesh: Timing,
    #[serde(skip_serializing_if = "Option::is_none")]
    mixed: Option<Timing>,
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
    if !args.bumpy && !args.volume.has_mesh() {
        return Err(Failure::Usage(
            "give the mesh with --mesh FRACTION (the volume's isosurface there), or --bumpy".into(),
        ));
    }
    let image = UVec2::splat(args.size);
    FrameDesc::new(image)
        .validate()
        .map_err(|e| Failure::Usage(format!("--size {}: {e}", args.size)))?;
    let mut settings = RenderSettings::default();
    let (name, shapes, mixed, cameras) = if args.bumpy {
        settings.background = bumpy::BACKGROUND;
        let cameras = (0..args.views)
            .map(|i| bumpy::camera(i, args.views, image))
            .collect::<Result<Vec<_>, _>>()?;
        let name = "bumpy sphere and 1024 spheres".to_string();
        (name, bumpy::shapes()?, None, cameras)
    } else {
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
        (loaded.name.clone(), shapes, Some(mixed), cameras)
    };
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
        renderers.push(Renderer::Cpu(
            CpuRenderer::new().with_surface_packets(false),
        ));
    }
    let scenes = 1 + usize::from(mixed.is_some());
    let mut progress = Progress::new(renderers.len() * scenes * cameras.len());
    let mut runs = Vec::new();
    // The view the two renderers' images are compared on.
    let kept = if mixed.is_some() { "mixed" } else { "mesh" };
    let mut firsts: Vec<Frame> = Vec::new();
    for renderer in &mut renderers {
        let name = match renderer {
            Renderer::Gpu(_) => "gpu",
            Renderer::Cpu(c) if c.uses_surface_packets() => "cpu",
            Renderer::Cpu(_) => "cpu 1-ray",
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
                // The GPU's and the first CPU's.
                if i == 0 && what == kept && keep.len() < 2 {
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
        let mixed_timing = match &mixed {
            Some(mixed) => Some(timing(mixed, "mixed", &mut firsts)?),
            None => None,
        };
        runs.push(Run {
            renderer: RendererInfo::of(renderer),
            camera_rays: rays_of(renderer),
            mesh: mesh_timing,
            mixed: mixed_timing,
        });
    }
    let gpu_cpu_ssim = match firsts.as_slice() {
        [g, c] if !args.no_gpu => ssim(g, c).ok(),
        _ => None,
    };
    let report = SurfacesReport {
        benchmark: "surfaces",
        machine: Machine::this(),
        image: image.to_array(),
        volume: name,
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
    print!("renderer   first mesh ms   mesh ms   Mrays/s");
    println!(
        "{}",
        if mixed.is_some() {
            "   first mixed ms   mixed ms"
        } else {
            ""
        }
    );
    for (run, renderer) in report.runs.iter().zip(&renderers) {
        let name = match renderer {
            Renderer::Gpu(g) => g.adapter().name.clone(),
            Renderer::Cpu(c) if c.uses_surface_packets() => "cpu".to_string(),
            Renderer::Cpu(_) => "cpu, rays one by one".to_string(),
        };
        print!(
            "{name:<10} {:>14.1} {:>9.1} {:>9.2}",
            run.mesh.first_ms,
            run.mesh.mean_ms,
            run.mesh.rays_per_second / 1e6,
        );
        match &run.mixed {
            Some(m) => println!(" {:>16.1} {:>10.1}", m.first_ms, m.mean_ms),
            None => println!(),
        }
    }
    if let Some(s) = report.gpu_cpu_ssim {
        println!("GPU against CPU, first view of the {kept}: SSIM {s:.4}");
    }
    println!("written to {}", args.json.display());
    Ok(())
}

/// How a renderer sends camera rays to their first surface (the CPU's).
fn rays_of(renderer: &Renderer) -> Option<&'static str> {
    match renderer {
        Renderer::Gpu(_) => None,
        Renderer::Cpu(c) if c.uses_surface_packets() => Some("packets"),
        Renderer::Cpu(_) => Some("single"),
    }
}
