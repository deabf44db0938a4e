//! The CPU renderer's fast path (packets of sixteen samples in AVX-512
//! lanes, or eight in AVX2 lanes) held to the scalar reference and to
//! each other, and `auto` choosing the CPU over a software adapter.

use crate::common;

use std::sync::Arc;

use anari_library_caveray::data::{concentric_shells, preset, shepp_logan};
use anari_library_caveray::render::simd::Level;
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, AutoChoice, Backend, CpuRenderer, FrameDesc, GpuRenderer, RenderSettings, Renderer,
    Shading,
};
use anari_library_caveray::scene::{Scene, TransferFunction};
use common::render::{four_cameras, off_axis_wall};
use glam::{UVec2, Vec4};

#[test]
fn packets_match_the_scalar_reference_sample_for_sample() {
    let fast = CpuRenderer::new();
    assert!(
        fast.uses_packets() || !cfg!(target_arch = "x86_64"),
        "this x86_64 CPU has no AVX2/FMA, so the fast path is not tested here"
    );
    // Every width this CPU runs, the widest first.
    let widths: Vec<CpuRenderer> = [Level::Avx512, Level::Avx2]
        .into_iter()
        .filter_map(CpuRenderer::with_simd)
        .collect();
    if !Level::Avx512.runs() {
        eprintln!("this CPU has no AVX-512: its packets are not tested here");
    }
    let reference = CpuRenderer::reference();
    assert!(!reference.uses_packets());
    let shells = Scene::shared(
        Arc::new(concentric_shells(40).into()),
        Arc::new(preset("shells").unwrap().with_unit_distance(0.2).unwrap()),
    );
    let opaque = Scene::new(
        shepp_logan(32),
        TransferFunction::new(vec![Vec4::ONE], vec![0.0, 1.0], (0.0, 1.0), 0.02).unwrap(),
    );
    let phantom = Scene::new(shepp_logan(32), preset("phantom").unwrap());
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(48, 40);
    let desc = FrameDesc::new(size).with_depth();
    for (name, scene) in [
        ("shells", &shells),
        ("opaque", &opaque),
        ("phantom", &phantom),
    ] {
        for (camera, rays) in four_cameras(&screen, eye, size) {
            for shading in [Shading::None, Shading::Shadows, Shading::Directional(4)] {
                // Skipping off: both march every step, so the counts agree.
                let settings = RenderSettings {
                    shading,
                    skipping: false,
                    ..Default::default()
                };
                let b = reference.render(scene, &rays, &settings, &desc).unwrap();
                let frames: Vec<_> = widths
                    .iter()
                    .map(|w| w.render(scene, &rays, &settings, &desc).unwrap())
                    .collect();
                let what = format!("{name} {camera} {shading}");
                for other in &frames[1..] {
                    // Each sample alike; the lanes' sums in another order.
                    let (a, other) = (&frames[0], other);
                    let s = ssim(a, other).unwrap();
                    assert!(s >= 0.99995, "{what}: AVX-512 against AVX2: SSIM {s}");
                    assert_eq!(a.samples, other.samples, "{what}: samples by width");
                }
                for a in &frames {
                    let s = ssim(a, &b).unwrap();
                    assert!(s >= 0.9999, "{what}: SSIM {s}");
                    assert_eq!(a.samples, b.samples, "{what}: samples");
                    let (da, db) = (a.depth.as_ref().unwrap(), b.depth.as_ref().unwrap());
                    let worst = da
                        .iter()
                        .zip(db)
                        .filter(|(x, y)| x.is_finite() || y.is_finite())
                        .map(|(x, y)| (x - y).abs())
                        .fold(0.0f32, f32::max);
                    assert!(worst < 1e-3, "{what}: depth differs by {worst}");
                }
            }
        }
    }
}

#[test]
fn auto_renders_on_the_cpu_where_the_only_adapter_is_software() {
    let adapter = GpuRenderer::probe().expect("a Vulkan adapter (lavapipe on CI)");
    let (renderer, why) = Renderer::choose(Backend::Auto).unwrap();
    if adapter.device_type == wgpu::DeviceType::Cpu {
        assert_eq!(renderer.backend(), Backend::Cpu);
        let why = why.expect("a reason for the CPU");
        assert!(matches!(why, AutoChoice::SoftwareAdapter(_)), "{why:?}");
        let said = why.to_string();
        assert!(
            said.contains(&adapter.name) && said.contains("faster"),
            "{said}"
        );
    } else {
        assert_eq!(renderer.backend(), Backend::Gpu);
        assert!(why.is_none());
    }
    // `gpu` still takes the software adapter when asked.
    let (gpu, why) = Renderer::choose(Backend::Gpu).unwrap();
    assert_eq!(gpu.backend(), Backend::Gpu);
    assert!(why.is_none());
}
