//! The GPU warp passes against their CPU reference (src/render/warp/):
//! for a head-mounted view that stepped and turned and for a CAVE wall
//! whose eye moved, every mode's GPU image is the CPU's (SSIM >= 0.995,
//! colors within 2e-3 in most pixels); a second source is uploaded, not
//! the first one shown again; bad input fails as on the CPU.

use crate::common;

use std::sync::atomic::AtomicBool;

use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays, RayGen};
use anari_library_caveray::render::warp::{warp, Source, Timeline, WarpMode, WarpSettings, Warped};
use anari_library_caveray::render::{
    ssim, ColorFormat, CpuRenderer, Frame, FrameDesc, RenderSettings, Renderer,
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

#[test]
fn the_gpu_captures_the_cpus_color_depth_and_layers() {
    use anari_library_caveray::scene::{AlphaMode, ColorSource, OpacitySource, SurfaceMaterial};
    use glam::Vec3;
    let mut g = gpu();
    // The phantom, and the phantom with an opaque and a translucent ball
    // in it, each of which takes a layer.
    let ball = |centre: Vec3, r: f32, opacity: f32, alpha: AlphaMode| {
        common::render::balls(
            vec![centre],
            r,
            SurfaceMaterial {
                color: ColorSource::Constant(Vec3::new(0.9, 0.5, 0.2)),
                opacity: OpacitySource::Constant(opacity),
                alpha,
                pbr: None,
            },
        )
    };
    let with_balls = phantom(32)
        .with_shapes(vec![
            ball(Vec3::new(-0.3, 0.25, 0.6), 0.25, 1.0, AlphaMode::Opaque),
            ball(Vec3::new(0.25, -0.2, 0.0), 0.4, 0.4, AlphaMode::Blend),
        ])
        .unwrap();
    for (what, scene) in [
        ("the phantom", phantom(32)),
        ("balls in the phantom", with_balls),
    ] {
        captured_alike(&mut g, what, &scene);
    }
}

fn captured_alike(g: &mut anari_library_caveray::render::GpuRenderer, what: &str, scene: &Scene) {
    let from = pinhole(DVec3::new(0.2, 0.1, 3.5), DVec3::ZERO);
    let settings = RenderSettings::default();
    let cpu = capture(scene, &from);
    let (on_gpu, ms) = g
        .capture(scene, &from, &settings, SIZE, 4, &AtomicBool::new(false))
        .unwrap();
    assert!(ms >= 0.0);
    assert_eq!(
        (on_gpu.size, on_gpu.k, on_gpu.layers.len()),
        (SIZE, 4, cpu.layers.len())
    );
    let as_warped = |s: &Source| Warped {
        size: s.size,
        color: s.color.clone(),
        depth: s.depth.clone(),
    };
    compare(
        &format!("{what}: captured color"),
        &as_warped(&cpu),
        &as_warped(&on_gpu),
    );
    let depths = cpu.depth.iter().zip(&on_gpu.depth);
    let same_depth = depths
        .filter(|(a, b)| (a.is_infinite() && b.is_infinite()) || (*a - *b).abs() < 1e-3)
        .count();
    assert!(
        same_depth as f64 >= 0.97 * cpu.depth.len() as f64,
        "{what}: depths differ"
    );
    // Layers agree to within a step of their extents (the GPU takes every
    // segment as a full step), and what they warp to is the CPU's.
    let step = 2.0 / 31.0 / 2.0;
    let close = cpu.layers.iter().zip(&on_gpu.layers).filter(|(a, b)| {
        (a.start - b.start).abs() <= step + 1e-3
            && (a.end - b.end).abs() <= step + 1e-3
            && (a.color - b.color).abs().max_element() < 2e-3
    });
    assert!(
        close.count() as f64 >= 0.97 * cpu.layers.len() as f64,
        "{what}: layers differ"
    );
    let target = pinhole(DVec3::new(0.5, 0.1, 3.5), DVec3::new(0.3, 0.0, 0.0));
    let layers = WarpSettings::new(WarpMode::Layers, scene.bounds());
    compare(
        &format!("{what}: layers from the GPU's capture"),
        &warp(&cpu, &target, SIZE, &layers).unwrap(),
        &g.warp(&on_gpu, &target, SIZE, &layers).unwrap().0,
    );
    let e = g
        .capture(scene, &from, &settings, SIZE, 9, &AtomicBool::new(false))
        .unwrap_err();
    assert!(e.to_string().contains("at most 8 layers"), "{e}");
}

#[test]
fn the_timeline_runs_on_the_gpu_as_on_the_cpu() {
    let scene = phantom(24);
    let still = pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::ZERO);
    let moving = |t: f64| {
        Ok(pinhole(
            DVec3::new(1.5 * t, 0.0, 3.5),
            DVec3::new(1.5 * t, 0.0, 0.0),
        ))
    };
    let timeline = Timeline {
        hz: 60.0,
        duration: 0.1,
        size: SIZE,
        cells: UVec2::new(3, 3),
        bias: 1.2,
        layers: 4,
        render_ms: Some(30.0),
        warp_ms: 1.0,
        modes: WarpMode::ALL.to_vec(),
        warp: WarpSettings::new(WarpMode::None, scene.bounds()),
    };
    let settings = RenderSettings::default();
    let run = |r: &mut Renderer, view: &dyn Fn(f64) -> Result<RayGen, String>| {
        timeline
            .run(r, &scene, &settings, view, &mut |_| {})
            .unwrap()
    };
    let mut on_gpu = Renderer::Gpu(Box::new(gpu()));
    let mut on_cpu = Renderer::Cpu(CpuRenderer::new());
    for r in run(&mut on_gpu, &|_| Ok(still)) {
        assert!(
            r.dssim.iter().all(|&d| d < 3e-3),
            "still head on the GPU: {r:?}"
        );
    }
    let (g, c) = (run(&mut on_gpu, &moving), run(&mut on_cpu, &moving));
    assert_eq!(g.len(), c.len());
    for (a, b) in g.iter().zip(&c) {
        assert_eq!(
            a.age_ms, b.age_ms,
            "simulated times do not depend on the renderer"
        );
        for (x, y) in a.dssim.iter().zip(&b.dssim) {
            assert!(
                (x - y).abs() < 0.01,
                "GPU {:?} vs CPU {:?}",
                a.dssim,
                b.dssim
            );
        }
    }
}
