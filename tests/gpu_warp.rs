//! The GPU warp passes against their CPU reference (src/render/warp/):
//! for a head-mounted view that stepped and turned and for a CAVE wall
//! whose eye moved, every mode's GPU image is the CPU's (SSIM >= 0.995,
//! colours within 2e-3 in most pixels); a second source is uploaded, not
//! the first one shown again; bad input fails as on the CPU.

mod common;

use std::sync::atomic::AtomicBool;

use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays, RayGen};
use anari_library_caveray::render::warp::{warp, Source, WarpMode, WarpSettings, Warped};
use anari_library_caveray::render::{
    ssim, ColorFormat, CpuRenderer, Frame, FrameDesc, RenderSettings,
};
use anari_library_caveray::scene::Scene;
use common::render::{four_cameras, gpu, off_axis_wall, phantom};
use glam::{DVec3, UVec2};

const SIZE: UVec2 = UVec2::new(40, 36);

fn pinhole(eye: DVec3, look: DVec3) -> RayGen {
    PinholeCamera::new(
        eye,
        look - eye,
        DVec3::Y,
        0.9,
        40.0 / 36.0,
        ImageRegion::FULL,
    )
    .unwrap()
    .ray_gen(SIZE)
}

fn capture(scene: &Scene, rays: &RayGen) -> Source {
    CpuRenderer::new()
        .capture(
            scene,
            rays,
            &RenderSettings::default(),
            SIZE,
            4,
            &AtomicBool::new(false),
        )
        .unwrap()
}

fn frame(w: &Warped) -> Frame {
    w.frame(
        &FrameDesc::new(SIZE).with_color(ColorFormat::Rgba32F),
        RenderSettings::default().background,
    )
    .unwrap()
}

fn compare(name: &str, cpu: &Warped, gpu: &Warped) {
    let s = ssim(&frame(cpu), &frame(gpu)).unwrap();
    let close = cpu
        .color
        .iter()
        .zip(&gpu.color)
        .filter(|(a, b)| (**a - **b).abs().max_element() <= 2e-3)
        .count();
    let share = close as f64 / cpu.color.len() as f64;
    assert!(
        s >= 0.995 && share >= 0.97,
        "{name}: SSIM {s}, {share} of pixels within 2e-3"
    );
    assert!(
        cpu.color.iter().any(|c| c.w > 0.1),
        "{name}: nothing to compare"
    );
}

#[test]
fn every_gpu_warp_is_its_cpu_reference() {
    let mut g = gpu();
    let scene = phantom(32);
    let from = pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::ZERO);
    let source = capture(&scene, &from);
    let (screen, eye) = off_axis_wall();
    let wall_from = four_cameras(&screen, eye, SIZE)[0].1;
    let wall_to = four_cameras(&screen, eye + DVec3::new(0.2, 0.1, 0.0), SIZE)[0].1;
    let wall_source = capture(&scene, &wall_from);
    let cases = [
        (
            "step",
            &source,
            pinhole(DVec3::new(0.3, 0.0, 3.5), DVec3::new(0.3, 0.0, 0.0)),
        ),
        (
            "turn",
            &source,
            pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::new(0.4, 0.1, 0.0)),
        ),
        ("wall", &wall_source, wall_to),
    ];
    for (name, source, target) in cases {
        for mode in WarpMode::ALL {
            let settings = WarpSettings::new(mode, scene.bounds());
            let cpu = warp(source, &target, SIZE, &settings).unwrap();
            let (on_gpu, ms) = g.warp(source, &target, SIZE, &settings).unwrap();
            assert!(ms >= 0.0);
            compare(&format!("{name} {}", mode.name()), &cpu, &on_gpu);
        }
    }
}

#[test]
fn a_new_source_is_uploaded_and_bad_input_fails_as_on_the_cpu() {
    let mut g = gpu();
    let scene = phantom(24);
    let target = pinhole(DVec3::new(0.2, 0.0, 3.5), DVec3::new(0.2, 0.0, 0.0));
    let settings = WarpSettings::new(WarpMode::Quad, scene.bounds());
    let near = capture(&scene, &pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::ZERO));
    let far = capture(&scene, &pinhole(DVec3::new(0.0, 0.0, 6.0), DVec3::ZERO));
    let first = g.warp(&near, &target, SIZE, &settings).unwrap().0;
    let second = g.warp(&far, &target, SIZE, &settings).unwrap().0;
    compare(
        "second source",
        &warp(&far, &target, SIZE, &settings).unwrap(),
        &second,
    );
    assert_ne!(
        first.color, second.color,
        "the second source was not uploaded"
    );

    let plain = CpuRenderer::new()
        .capture(
            &scene,
            &target,
            &RenderSettings::default(),
            SIZE,
            0,
            &AtomicBool::new(false),
        )
        .unwrap();
    let layers = WarpSettings::new(WarpMode::Layers, scene.bounds());
    let e = g.warp(&plain, &target, SIZE, &layers).unwrap_err();
    assert!(
        e.to_string()
            .contains("needs a source rendered with layers"),
        "{e}"
    );
    let e = g
        .warp(&near, &target, UVec2::new(0, 4), &settings)
        .unwrap_err();
    assert!(e.to_string().contains("at least 1x1"), "{e}");
    // Still usable.
    g.warp(&near, &target, SIZE, &settings).unwrap();
}
