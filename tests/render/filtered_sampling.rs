//! Filtered GPU sampling (one hardware-filtered volume fetch and one
//! stepped-table fetch per sample) against the exact path: close to it,
//! the same samples taken, the last short segment still corrected; and
//! level of detail on top of it, fewer samples for a measured likeness.

use crate::common;

use std::sync::Arc;

use anari_library_caveray::data::{concentric_shells, preset, shepp_logan, solid_box};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, ColorData, ColorFormat, FrameDesc, RenderSettings, Sampling, Shading,
};
use anari_library_caveray::scene::{Filter, Scene, TransferFunction};
use common::render::{axis_camera, four_cameras, gpu, off_axis_wall};
use glam::{UVec2, Vec4};

fn settings(sampling: Sampling, shading: Shading) -> RenderSettings {
    RenderSettings {
        sampling,
        shading,
        ..Default::default()
    }
}

#[test]
fn filtered_sampling_stays_close_to_the_exact_path() {
    let mut gpu = gpu();
    assert!(
        gpu.filters(),
        "{} cannot filter 32-bit floats: filtered sampling is untested here",
        gpu.adapter().name
    );
    let shells = Scene::shared(
        Arc::new(concentric_shells(48).into()),
        Arc::new(preset("shells").unwrap().with_unit_distance(0.2).unwrap()),
    );
    let phantom = Scene::new(shepp_logan(48), preset("phantom").unwrap());
    let nearest = Scene::new(
        shepp_logan(24).with_filter(Filter::Nearest),
        preset("phantom").unwrap(),
    );
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(64, 56);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let desc = FrameDesc::new(size);
    for (name, scene) in [
        ("shells", &shells),
        ("phantom", &phantom),
        ("nearest", &nearest),
    ] {
        for shading in [Shading::None, Shading::Shadows] {
            let exact = gpu
                .render(scene, &rays, &settings(Sampling::Exact, shading), &desc)
                .unwrap();
            let filtered = gpu
                .render(scene, &rays, &settings(Sampling::Filtered, shading), &desc)
                .unwrap();
            let s = ssim(&filtered, &exact).unwrap();
            println!(
                "{name} {shading}: SSIM {s:.5}, samples {} / {}",
                filtered.samples, exact.samples
            );
            assert!(s >= 0.98, "{name} {shading}: filtered vs exact SSIM {s}");
            let drift = filtered.samples.abs_diff(exact.samples) as f64 / exact.samples as f64;
            assert!(drift < 0.01, "{name} {shading}: samples differ by {drift}");
        }
    }
}

#[test]
fn a_filtered_box_keeps_the_closed_form_transmittance() {
    // A solid box of per-unit opacity a, crossed along its axis over
    // length 2: the transmittance is (1 - a)^(2 / unit) whatever the step,
    // which holds only if the short last segment is corrected too.
    let mut gpu = gpu();
    let (a, unit) = (0.2f32, 0.5f32);
    let tf = TransferFunction::new(vec![Vec4::ONE], vec![a], (0.0, 1.0), unit).unwrap();
    let scene = Scene::new(solid_box(13), tf);
    let (screen, eye) = axis_camera(4.0, 0.1);
    let size = UVec2::new(5, 5);
    let rays = off_axis(&screen, eye, size);
    let desc = FrameDesc {
        color: ColorFormat::Rgba32F,
        ..FrameDesc::new(size)
    };
    let want = 1.0 - (1.0 - a).powf(2.0 / unit);
    for step_factor in [1.0, 0.7, 1.3] {
        let s = RenderSettings {
            step_factor,
            background: Vec4::ZERO,
            termination: 1.01,
            ..settings(Sampling::Filtered, Shading::None)
        };
        let frame = gpu.render(&scene, &rays, &s, &desc).unwrap();
        let ColorData::Rgba32F(c) = &frame.color else {
            panic!("asked for RGBA32F")
        };
        let centre = 4 * (2 * 5 + 2);
        let got = c[centre + 3];
        assert!(
            (got - want).abs() < 2e-3,
            "step {step_factor}: alpha {got}, want {want}"
        );
    }
}

fn off_axis(
    screen: &anari_library_caveray::geometry::Screen,
    eye: glam::DVec3,
    size: UVec2,
) -> anari_library_caveray::geometry::RayGen {
    use anari_library_caveray::geometry::{OffAxisCamera, PrimaryRays};
    OffAxisCamera::new(*screen, eye).unwrap().ray_gen(size)
}

#[test]
fn level_of_detail_trades_samples_for_a_measured_likeness() {
    let mut gpu = gpu();
    let scene = Scene::shared(
        Arc::new(concentric_shells(96).into()),
        Arc::new(preset("shells").unwrap().with_unit_distance(0.2).unwrap()),
    );
    // Far enough that a pixel covers several voxels at the volume.
    let (screen, eye) = axis_camera(12.0, 2.0);
    let size = UVec2::new(64, 64);
    let rays = off_axis(&screen, eye, size);
    let desc = FrameDesc::new(size);
    let with = |lod: f32| RenderSettings {
        level_of_detail: lod,
        ..settings(Sampling::Filtered, Shading::None)
    };
    let exact = gpu
        .render(
            &scene,
            &rays,
            &settings(Sampling::Exact, Shading::None),
            &desc,
        )
        .unwrap();
    let full = gpu.render(&scene, &rays, &with(0.0), &desc).unwrap();
    let mut last = (1.0, 1.0);
    for lod in [0.5f32, 1.0, 2.0] {
        let coarse = gpu.render(&scene, &rays, &with(lod), &desc).unwrap();
        let s = ssim(&coarse, &exact).unwrap();
        let share = coarse.samples as f64 / full.samples as f64;
        println!("level of detail {lod}: SSIM {s:.4} to full detail, {share:.3} of the samples");
        // Coarser, cheaper, and never a different picture altogether.
        assert!(share < last.0 && s <= last.1 + 1e-3, "{lod}: {share} {s}");
        assert!(s >= 0.8, "level of detail {lod}: SSIM {s}");
        last = (share, s);
    }
    let half = gpu.render(&scene, &rays, &with(0.5), &desc).unwrap();
    let s = ssim(&half, &exact).unwrap();
    assert!(s >= 0.97, "level of detail 0.5: SSIM {s}");
    assert!(
        half.samples * 10 < full.samples * 7,
        "0.5 took {} of {}",
        half.samples,
        full.samples
    );
    // The CPU renders full detail whatever the setting.
    let cpu = anari_library_caveray::render::CpuRenderer::new();
    let a = cpu.render(&scene, &rays, &with(4.0), &desc).unwrap();
    let b = cpu.render(&scene, &rays, &with(0.0), &desc).unwrap();
    assert_eq!(a, b);
    // Off, it is the filtered path itself.
    let filtered = gpu
        .render(
            &scene,
            &rays,
            &settings(Sampling::Filtered, Shading::None),
            &desc,
        )
        .unwrap();
    assert_eq!(full, filtered);
    // Out of range is refused with the range.
    for bad in [-1.0, f32::NAN, 17.0] {
        let err = gpu.render(&scene, &rays, &with(bad), &desc).unwrap_err();
        assert!(
            err.to_string()
                .contains("level of detail must be in [0, 16]"),
            "{err}"
        );
    }
}
