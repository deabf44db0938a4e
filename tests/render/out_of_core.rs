//! Volumes larger than the GPU memory budget: paged through a pool that
//! holds part of their level chain, they render coarser where bricks are
//! not resident, and frames that do not wait for the loader converge, as
//! bricks arrive, to what a frame that waits renders.

use crate::common;

use std::sync::Arc;
use std::time::Duration;

use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::geometry::RayGen;
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, Frame, FrameDesc, GpuRenderer, RenderSettings, StreamWait,
};
use anari_library_caveray::scene::Scene;
use common::render::{four_cameras, gpu, off_axis_wall};
use glam::UVec2;

/// The view every test renders: one eye at an off-axis wall.
fn view() -> (RayGen, FrameDesc) {
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(48, 40);
    (four_cameras(&screen, eye, size)[0].1, FrameDesc::new(size))
}

/// Renders until every brick the view selects is resident, at most
/// `frames` frames; returns the frames' progress and the last image.
fn until_resident(gpu: &mut GpuRenderer, scene: &Scene, frames: usize) -> (Vec<f32>, Frame) {
    let (rays, desc) = view();
    let settings = RenderSettings::default();
    let mut progress = Vec::new();
    loop {
        let frame = gpu.render(scene, &rays, &settings, &desc).unwrap();
        progress.push(gpu.streaming().progress());
        if progress.last() == Some(&1.0) || progress.len() >= frames {
            return (progress, frame);
        }
        // A frame's worth of time for the loader, as a display would
        // leave it.
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn phantom_scene(n: u32) -> Scene {
    Scene::shared(
        Arc::new(shepp_logan(n).into()),
        Arc::new(preset("phantom").unwrap()),
    )
}

#[test]
fn a_volume_twice_the_budget_renders_coarser_and_converges_as_bricks_arrive() {
    // 40^3 float32 voxels (256000 bytes) in bricks of 8 texels: 216
    // full-detail bricks, 252 in the chain, 2048 bytes each.
    let scene = phantom_scene(40);
    let budget = 128_000;
    let mut whole = gpu();
    let (_, full) = until_resident(&mut whole, &scene, 1);

    let mut waiting = gpu();
    waiting.brick_every_volume(Some(8));
    waiting.set_memory_budget(Some(budget));
    let (progress, complete) = until_resident(&mut waiting, &scene, 1);
    assert_eq!(progress, [1.0], "a frame that waits has all it selected");
    let bytes = waiting.volume_bytes();
    assert!(bytes <= budget, "{bytes} bytes on the GPU");
    let coarse = ssim(&complete, &full).unwrap();
    println!("within the budget ({bytes} bytes): SSIM {coarse:.4} to full detail");
    assert!(coarse < 0.999, "half the budget cannot hold full detail");
    assert!(coarse > 0.5, "but shows the volume: {coarse}");

    let mut streaming = gpu();
    streaming.brick_every_volume(Some(8));
    streaming.set_memory_budget(Some(budget));
    streaming.set_stream_wait(StreamWait::Budget {
        wait: Duration::ZERO,
        bricks: 4,
    });
    let (progress, last) = until_resident(&mut streaming, &scene, 2000);
    println!(
        "{} frames: progress {:?} .. {:?}",
        progress.len(),
        &progress[..progress.len().min(4)],
        progress.last()
    );
    assert!(progress[0] < 1.0, "the first frame uploads four bricks");
    assert_eq!(progress.last(), Some(&1.0), "{progress:?}");
    let s = ssim(&last, &complete).unwrap();
    println!("converged: SSIM {s:.6} to the frame that waited");
    assert!(s >= 0.9999, "{s}");
}

#[test]
fn with_room_for_the_whole_chain_streamed_frames_converge_to_full_detail() {
    let scene = phantom_scene(30);
    let mut whole = gpu();
    let (_, full) = until_resident(&mut whole, &scene, 1);
    let mut streaming = gpu();
    streaming.brick_every_volume(Some(8));
    streaming.set_stream_wait(StreamWait::Budget {
        wait: Duration::ZERO,
        bricks: 4,
    });
    let (rays, desc) = view();
    let first = streaming
        .render(&scene, &rays, &RenderSettings::default(), &desc)
        .unwrap();
    let (progress, last) = until_resident(&mut streaming, &scene, 2000);
    assert_eq!(progress.last(), Some(&1.0), "{progress:?}");
    let (before, after) = (ssim(&first, &full).unwrap(), ssim(&last, &full).unwrap());
    println!("first frame SSIM {before:.4}, converged {after:.6}");
    assert!(after >= 0.9999, "{after}");
    assert!(before < after, "the first frame is coarser: {before}");
}

#[test]
fn under_level_of_detail_a_paged_volume_holds_coarser_bricks_and_keeps_the_likeness() {
    use anari_library_caveray::render::Sampling;
    let mut whole = gpu();
    if !whole.filters() {
        println!("{}: no filtered sampling", whole.adapter().name);
        return;
    }
    let scene = phantom_scene(40);
    let (rays, desc) = view();
    let with = |lod: f32| RenderSettings {
        sampling: Sampling::Filtered,
        level_of_detail: lod,
        ..Default::default()
    };
    let mut paged = gpu();
    paged.brick_every_volume(Some(8));
    let detail = paged.render(&scene, &rays, &with(0.0), &desc).unwrap();
    let all = paged.streaming().wanted;
    let coarse = paged.render(&scene, &rays, &with(2.0), &desc).unwrap();
    let fewer = paged.streaming().wanted;
    let mipmapped = whole.render(&scene, &rays, &with(2.0), &desc).unwrap();
    let (to_detail, mips_to_detail) = (
        ssim(&coarse, &detail).unwrap(),
        ssim(&mipmapped, &detail).unwrap(),
    );
    println!(
        "level of detail 2: {fewer} of {all} bricks; SSIM to full detail {to_detail:.4}, the mip-mapped texture's {mips_to_detail:.4}"
    );
    assert!(fewer < all, "{fewer} of {all}");
    // Each sample reads the level its footprint asks for (rounded to the
    // finer), where mip mapping blends two: as close to full detail.
    assert!(
        to_detail >= mips_to_detail - 0.02,
        "{to_detail} {mips_to_detail}"
    );
    assert!(to_detail < 0.999, "coarser than full detail: {to_detail}");
}
