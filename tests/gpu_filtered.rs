//! Filtered GPU sampling (one hardware-filtered volume fetch and one
//! stepped-table fetch per sample) against the exact path: close to it,
//! the same samples taken, the last short segment still corrected, and
//! refused in words where the adapter cannot filter 32-bit floats.

mod common;

use std::sync::Arc;

use anari_library_caveray::data::{concentric_shells, preset, shepp_logan, solid_box};
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
        Arc::new(concentric_shells(48)),
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
