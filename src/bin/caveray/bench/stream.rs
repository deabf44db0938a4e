//! `caveray bench stream`: a volume larger than the GPU memory budget,
//! paged. One frame that waits for every brick it selects (what a
//! complete frame within the budget looks like, and what it costs), then,
//! on a fresh renderer, frames that wait at most `--wait-ms` and upload
//! at most `--bricks` bricks each, as a display would render them, until
//! every brick they select is resident: per frame its time, the share of
//! its bricks resident and its SSIM to the complete frame. Writes JSON, a
//! chart of the convergence and a strip of frames.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anari_library_caveray::output::{
    frame_to_rgba, side_by_side, write_rgba_png, Chart, Series, XAxis,
};
use anari_library_caveray::render::stereo::{paper, HmdStereo};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, Frame, FrameDesc, GpuRenderer, RenderSettings, StreamWait,
};
use clap::Args;
use glam::{UVec2, Vec3};
use serde::Serialize;

use super::raycast::camera;
use super::runtime;
use crate::options::bytes;
use crate::progress::Progress;
use crate::report::{write_json, Adapter, Machine};
use crate::scene::{at, protocol_frame, VolumeArgs, PROTOCOL_UNITS};
use crate::Failure;

#[derive(Args)]
pub struct StreamArgs {
    #[command(flatten)]
    volume: VolumeArgs,
    /// Image width and height in pixels.
    #[arg(long, default_value_t = 256)]
    size: u32,
    /// Bytes of GPU memory the volume may take (K, M, G suffixes;
    /// default: half its voxels' bytes, so that it cannot be held whole).
    #[arg(long, value_parser = bytes)]
    budget: Option<u64>,
    /// Milliseconds a streamed frame waits for bricks.
    #[arg(long, default_value_t = 0.0)]
    wait_ms: f64,
    /// Bricks a streamed frame uploads at most.
    #[arg(long, default_value_t = 16)]
    bricks: u32,
    /// Bricks of this many texels a side (default 64).
    #[arg(long)]
    brick_texels: Option<u32>,
    /// Streamed frames at most.
    #[arg(long, default_value_t = 1000)]
    frames: usize,
    /// Where to write the results; the chart (.svg) and the strip of
    /// frames (.png) go beside it.
    #[arg(long, default_value = "out/bench/stream.json")]
    json: PathBuf,
}

#[derive(Serialize)]
struct StreamReport {
    benchmark: &'static str,
    machine: Machine,
    adapter: Adapter,
    image: [u32; 2],
    volume: String,
    dims: [u32; 3],
    /// The volume's voxels as stored, and as one texture would take them.
    voxel_bytes: u64,
    budget: u64,
    /// What the paged volume holds on the GPU: pool and page table.
    gpu_bytes: u64,
    wait_ms: f64,
    bricks_per_frame: u32,
    /// The frame that waited for every brick it selected: its time
    /// (pipelines, loading and upload included) and its bricks.
    complete_ms: f64,
    complete_bricks: u32,
    /// SSIM of the complete frame within the budget to one without a
    /// budget (where the adapter holds the volume whole).
    #[serde(skip_serializing_if = "Option::is_none")]
    budget_ssim: Option<f64>,
    frames: Vec<StreamedFrame>,
    /// Streamed frames until every brick selected was resident.
    converged_after: Option<usize>,
}

#[derive(Serialize)]
struct StreamedFrame {
    ms: f64,
    progress: f32,
    uploaded: u32,
    /// Against the complete frame.
    ssim: f64,
}

pub fn run(args: StreamArgs) -> Result<(), Failure> {
    let wait_ok = args.wait_ms.is_finite() && args.wait_ms >= 0.0;
    if args.size == 0 || args.frames == 0 || !wait_ok {
        return Err(Failure::Usage(format!(
            "need --size > 0, --frames > 0 and --wait-ms >= 0 (got {}, {}, {})",
            args.size, args.frames, args.wait_ms
        )));
    }
    let image = UVec2::splat(args.size);
    let desc = FrameDesc::new(image);
    desc.validate()
        .map_err(|e| Failure::Usage(format!("--size {}: {e}", args.size)))?;
    let setup = HmdStereo::protocol(args.size, paper::SPAN_PX);
    let radius = setup.radius.unwrap_or(paper::RADIUS_M);
    let rays = camera(1, 8, &setup, radius, image)?;
    let loaded = args.volume.load()?.with_stored_axes();
    let (lo, hi) = loaded.bounds();
    let extent = hi - lo;
    let size = extent.max_element() * (2.0 * radius as f32) / extent.length();
    let scene = loaded.placed(at(Vec3::ZERO, size), &protocol_frame(), PROTOCOL_UNITS)?;
    let grid = &scene.volumes()[0].volume;
    let voxel_bytes = grid.bytes();
    let settings = RenderSettings::default();

    let open = || -> Result<GpuRenderer, Failure> {
        let mut gpu = GpuRenderer::new().map_err(runtime)?;
        gpu.brick_every_volume(args.brick_texels);
        Ok(gpu)
    };
    let mut progress = Progress::new(3);
    let budget = args.budget.unwrap_or(voxel_bytes / 2);
    let full = GpuRenderer::new()
        .and_then(|mut whole| whole.render(&scene, &rays, &settings, &desc))
        .map_err(|e| e.to_string());
    progress.step(&match &full {
        Ok(_) => "without a budget: rendered".to_string(),
        Err(e) => format!("without a budget: {e}"),
    });
    let full = full.ok();

    let mut waiting = open()?;
    waiting.set_memory_budget(Some(budget));
    let t = Instant::now();
    let complete = waiting
        .render(&scene, &rays, &settings, &desc)
        .map_err(runtime)?;
    let complete_ms = t.elapsed().as_secs_f64() * 1e3;
    let complete_bricks = waiting.streaming().wanted;
    let gpu_bytes = waiting.volume_bytes();
    let adapter = Adapter::of(&waiting);
    progress.step(&format!(
        "complete frame within {budget} bytes: {complete_ms:.0} ms, {complete_bricks} bricks"
    ));
    drop(waiting);
    let budget_ssim = full.as_ref().and_then(|f| ssim(&complete, f).ok());

    let mut streaming = open()?;
    streaming.set_memory_budget(Some(budget));
    streaming.set_stream_wait(StreamWait::Budget {
        wait: Duration::from_secs_f64(args.wait_ms / 1e3),
        bricks: args.bricks,
    });
    let mut frames = Vec::new();
    let mut shown: Vec<(usize, Frame)> = Vec::new();
    let mut converged_after = None;
    for i in 0..args.frames {
        let t = Instant::now();
        let frame = streaming
            .render(&scene, &rays, &settings, &desc)
            .map_err(runtime)?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let s = streaming.streaming();
        frames.push(StreamedFrame {
            ms,
            progress: s.progress(),
            uploaded: s.uploaded,
            ssim: ssim(&frame, &complete).map_err(runtime)?,
        });
        let done = s.progress() >= 1.0;
        if (i + 1).is_power_of_two() || done {
            shown.push((i + 1, frame));
        }
        if done {
            converged_after = Some(i + 1);
            break;
        }
    }
    progress.step(&format!("{} streamed frames", frames.len()));

    let report = StreamReport {
        benchmark: "stream",
        machine: Machine::this(),
        adapter,
        image: image.to_array(),
        volume: loaded.name.clone(),
        dims: grid.dims().to_array(),
        voxel_bytes,
        budget,
        gpu_bytes,
        wait_ms: args.wait_ms,
        bricks_per_frame: args.bricks,
        complete_ms,
        complete_bricks,
        budget_ssim,
        frames,
        converged_after,
    };
    write_json(&report, &args.json)?;
    let chart = Chart {
        title: "Streamed frames converging",
        x_label: "frame",
        y_label: "%",
        y_range: (0.0, 100.0),
        series: &[
            Series {
                name: "bricks resident".into(),
                points: series(&report.frames, |f| f64::from(f.progress)),
            },
            Series {
                name: "SSIM to complete".into(),
                points: series(&report.frames, |f| f.ssim),
            },
        ],
        x_axis: XAxis::Linear,
    };
    let svg = args.json.with_extension("svg");
    std::fs::write(&svg, chart.to_svg())
        .map_err(|e| Failure::Runtime(format!("{}: {e}", svg.display())))?;
    let mut strip: Vec<_> = shown.iter().map(|(_, f)| frame_to_rgba(f)).collect();
    strip.push(frame_to_rgba(&complete));
    let png = args.json.with_extension("png");
    write_rgba_png(&side_by_side(&strip.iter().collect::<Vec<_>>(), 8), &png).map_err(runtime)?;

    let mib = |b: u64| b as f64 / f64::from(1 << 20);
    println!(
        "{} {}x{}x{} ({:.1} MiB) on {}, budget {:.1} MiB ({:.1} MiB on the GPU)",
        report.volume,
        report.dims[0],
        report.dims[1],
        report.dims[2],
        mib(voxel_bytes),
        report.adapter.name,
        mib(budget),
        mib(gpu_bytes)
    );
    println!(
        "complete frame: {complete_ms:.0} ms, {complete_bricks} bricks{}",
        budget_ssim.map_or(String::new(), |s| format!(", SSIM {s:.4} to full detail"))
    );
    println!("frame      ms  resident  uploaded    SSIM");
    for (i, f) in report.frames.iter().enumerate() {
        if (i + 1).is_power_of_two() || i + 1 == report.frames.len() {
            println!(
                "{:>5} {:>7.1} {:>8.1}% {:>9} {:>7.4}",
                i + 1,
                f.ms,
                100.0 * f.progress,
                f.uploaded,
                f.ssim
            );
        }
    }
    match converged_after {
        Some(n) => println!("every selected brick resident after {n} frames"),
        None => println!("not converged within {} frames", args.frames),
    }
    println!(
        "written to {}, {} (frames {}, then the complete one) and {}",
        args.json.display(),
        png.display(),
        shown
            .iter()
            .map(|(i, _)| i.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        svg.display()
    );
    Ok(())
}

fn series(frames: &[StreamedFrame], y: impl Fn(&StreamedFrame) -> f64) -> Vec<(f64, f64)> {
    frames
        .iter()
        .enumerate()
        .map(|(i, f)| ((i + 1) as f64, 100.0 * y(f)))
        .collect()
}
