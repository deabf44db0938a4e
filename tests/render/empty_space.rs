//! Empty-space skipping changes how fast a frame renders, never what it
//! shows: on the CPU and the GPU, over one volume and several, nearest and
//! linear filters, clip planes and shading, the image with skipping is the
//! image without it (SSIM >= 0.9999), while the shells scene takes far
//! fewer samples; a new table over the same grid finds its own bricks.

use crate::common;

use std::sync::Arc;

use anari_library_caveray::data::{concentric_shells, preset, shepp_logan};
use anari_library_caveray::geometry::RayGen;
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, ClipPlanes, Frame, FrameDesc, RenderSettings, Renderer, Shading,
};
use anari_library_caveray::scene::{
    Filter, ObjectIds, PlacedVolume, Scene, StructuredVolume, TransferFunction,
};
use common::render::{four_cameras, off_axis_wall, renderers};
use glam::{Mat4, UVec2, Vec3, Vec4};

const IDENTICAL: f64 = 0.9999;

fn shells_tf() -> Arc<TransferFunction> {
    Arc::new(preset("shells").unwrap().with_unit_distance(0.05).unwrap())
}

fn shells(n: u32) -> Scene {
    Scene::shared(Arc::new(concentric_shells(n).into()), shells_tf())
}

/// Shells and a turned, shrunken phantom overlapping them.
fn two_volumes() -> Scene {
    let place = |volume: StructuredVolume, tf: Arc<TransferFunction>, transform| PlacedVolume {
        volume: Arc::new(volume.into()),
        transfer_function: tf,
        transform,
        ids: ObjectIds::NONE,
    };
    Scene::placed(vec![
        place(concentric_shells(40), shells_tf(), Mat4::IDENTITY),
        place(
            shepp_logan(24),
            Arc::new(preset("phantom").unwrap()),
            Mat4::from_translation(Vec3::new(0.5, 0.2, 0.3))
                * Mat4::from_rotation_y(0.7)
                * Mat4::from_scale(Vec3::splat(0.6)),
        ),
    ])
    .unwrap()
}

fn rays(size: UVec2) -> RayGen {
    let (screen, eye) = off_axis_wall();
    four_cameras(&screen, eye, size)[0].1
}

fn render(r: &mut Renderer, scene: &Scene, settings: &RenderSettings, skipping: bool) -> Frame {
    let size = UVec2::new(48, 40);
    let settings = RenderSettings {
        skipping,
        ..settings.clone()
    };
    r.render(scene, &rays(size), &settings, &FrameDesc::new(size))
        .unwrap()
}

fn cases() -> Vec<(&'static str, Scene, RenderSettings)> {
    let plain = RenderSettings::default();
    let clipped = RenderSettings {
        clip_planes: ClipPlanes::new(&[Vec4::new(0.3, 0.2, 1.0, 0.25)]).unwrap(),
        ..plain.clone()
    };
    let shadows = RenderSettings {
        shading: Shading::Shadows,
        ..plain.clone()
    };
    let nearest = Scene::shared(
        Arc::new(concentric_shells(32).with_filter(Filter::Nearest).into()),
        shells_tf(),
    );
    vec![
        ("shells", shells(48), plain.clone()),
        (
            "phantom",
            Scene::new(shepp_logan(32), preset("phantom").unwrap()),
            plain.clone(),
        ),
        ("two volumes", two_volumes(), plain.clone()),
        ("nearest", nearest, plain.clone()),
        ("clip plane", shells(40), clipped),
        ("shadows", two_volumes(), shadows),
    ]
}

#[test]
fn skipping_leaves_every_image_as_it_was_on_both_renderers() {
    for (name, mut r) in renderers() {
        for (case, scene, settings) in cases() {
            let off = render(&mut r, &scene, &settings, false);
            let on = render(&mut r, &scene, &settings, true);
            let s = ssim(&on, &off).unwrap();
            println!(
                "{name} {case:>12}: SSIM {s:.6}, samples {} of {}",
                on.samples, off.samples
            );
            assert!(s >= IDENTICAL, "{name} {case}: SSIM {s} with skipping");
            assert!(
                on.samples <= off.samples,
                "{name} {case}: skipping took more samples ({} > {})",
                on.samples,
                off.samples
            );
        }
    }
}

#[test]
fn skipping_leaps_over_the_air_between_the_shells() {
    for (name, mut r) in renderers() {
        let scene = shells(64);
        let settings = RenderSettings::default();
        let off = render(&mut r, &scene, &settings, false);
        let on = render(&mut r, &scene, &settings, true);
        let share = on.samples as f64 / off.samples as f64;
        println!(
            "{name}: {} of {} samples ({share:.3})",
            on.samples, off.samples
        );
        assert!(share < 0.8, "{name}: skipping kept {share} of the samples");
    }
}

#[test]
fn the_gpu_and_the_cpu_skip_the_same_samples() {
    let mut both = renderers();
    let scene = two_volumes();
    let settings = RenderSettings::default();
    let frames: Vec<Frame> = both
        .iter_mut()
        .map(|(_, r)| render(r, &scene, &settings, true))
        .collect();
    let (gpu, cpu) = (&frames[0], &frames[1]);
    let s = ssim(gpu, cpu).unwrap();
    // Rounding may move a sample across a brick face; a handful, no more.
    let diff = gpu.samples.abs_diff(cpu.samples) as f64 / cpu.samples as f64;
    println!(
        "SSIM {s:.6}, samples GPU {} CPU {}",
        gpu.samples, cpu.samples
    );
    assert!(s >= 0.99, "GPU vs CPU with skipping: SSIM {s}");
    assert!(diff < 1e-3, "GPU and CPU sample counts differ by {diff}");
}

#[test]
fn a_new_table_over_the_same_grid_finds_its_own_clear_bricks() {
    // First a table that leaves the air and the inner shells' flanks
    // clear, then one that shows every value: bricks kept from the first
    // would cut the second's haze.
    let grid = Arc::new(concentric_shells(40).into());
    let narrow = shells_tf();
    let everything = Arc::new(
        TransferFunction::new(
            vec![Vec4::new(0.4, 0.6, 1.0, 1.0)],
            vec![0.02, 0.3],
            (0.0, 1.0),
            0.05,
        )
        .unwrap(),
    );
    for (name, mut r) in renderers() {
        let settings = RenderSettings::default();
        let first = Scene::shared(Arc::clone(&grid), Arc::clone(&narrow));
        render(&mut r, &first, &settings, true);
        let second = Scene::shared(Arc::clone(&grid), Arc::clone(&everything));
        let on = render(&mut r, &second, &settings, true);
        let off = render(&mut r, &second, &settings, false);
        let s = ssim(&on, &off).unwrap();
        assert!(s >= IDENTICAL, "{name}: SSIM {s} after the table changed");
        assert_eq!(on.samples, off.samples, "{name}: nothing is clear now");
    }
}
