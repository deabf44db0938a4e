//! AMR fields on both renderers: one, two and three levels of one smooth
//! function render as the function on the finest level's grid, on an
//! off-axis wall, shaded or not; the GPU samples as the CPU reference;
//! an AMR field shares a scene with a grid; skipping leaps over what the
//! table hides and leaves the image alone.

use crate::common;

use std::sync::Arc;

use anari_library_caveray::data::{finest_grid, preset, refined, shepp_logan, smooth_waves};
use anari_library_caveray::geometry::{OffAxisCamera, PrimaryRays, RayGen};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{ssim, Frame, FrameDesc, RenderSettings, Renderer, Shading};
use anari_library_caveray::scene::{
    ObjectIds, PlacedVolume, Scene, SpatialField, TransferFunction,
};
use common::render::{off_axis_wall, renderers};
use glam::{Mat4, UVec2, Vec3, Vec4};

const SIZE: UVec2 = UVec2::new(48, 48);

fn wall_rays() -> RayGen {
    let (screen, eye) = off_axis_wall();
    OffAxisCamera::new(screen, eye).unwrap().ray_gen(SIZE)
}

fn render(r: &mut Renderer, scene: &Scene, settings: &RenderSettings) -> Frame {
    r.render(scene, &wall_rays(), settings, &FrameDesc::new(SIZE))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Bands of color over the waves' values, clear below 0.4.
fn bands() -> TransferFunction {
    TransferFunction::new(
        vec![
            Vec4::new(0.1, 0.3, 0.9, 1.0),
            Vec4::new(0.2, 0.8, 0.4, 1.0),
            Vec4::new(0.9, 0.7, 0.1, 1.0),
            Vec4::new(0.9, 0.2, 0.1, 1.0),
        ],
        vec![0.0, 0.0, 0.5, 0.9],
        (0.3, 1.0),
        0.2,
    )
    .unwrap()
}

#[test]
fn refined_levels_render_as_the_finest_grid_of_the_same_function() {
    let n = 32;
    let reference = Scene::new(finest_grid(n, smooth_waves), bands());
    let levels: Vec<Scene> = (1..=3)
        .map(|l| Scene::new(refined(n, l, smooth_waves).unwrap(), bands()))
        .collect();
    for (name, mut r) in renderers() {
        for shading in [Shading::None, Shading::Shadows, Shading::Ao] {
            let settings = RenderSettings {
                shading,
                ..RenderSettings::default()
            };
            let want = render(&mut r, &reference, &settings);
            let s: Vec<f64> = levels
                .iter()
                .map(|scene| ssim(&render(&mut r, scene, &settings), &want).unwrap())
                .collect();
            eprintln!(
                "{name} {shading:?}: SSIM one level {:.5}, two {:.5}, three {:.5}",
                s[0], s[1], s[2]
            );
            // One level is the grid, shifted by nothing; more levels
            // read the coarse cells where the fine ones end.
            assert!(
                s[0] >= 0.9999,
                "{name} {shading:?}: one level SSIM {}",
                s[0]
            );
            assert!(s[1] >= 0.99, "{name} {shading:?}: two levels SSIM {}", s[1]);
            assert!(
                s[2] >= 0.99,
                "{name} {shading:?}: three levels SSIM {}",
                s[2]
            );
        }
    }
}

#[test]
fn an_amr_field_and_a_grid_share_a_scene_and_skipping_leaves_the_image_alone() {
    let amr: Arc<SpatialField> = Arc::new(refined(32, 3, smooth_waves).unwrap().into());
    let grid: Arc<SpatialField> = Arc::new(shepp_logan(16).into());
    let place = |volume: &Arc<SpatialField>, tf: TransferFunction, m: Mat4| PlacedVolume {
        volume: Arc::clone(volume),
        transfer_function: Arc::new(tf),
        transform: m,
        ids: ObjectIds::NONE,
    };
    let both = Scene::placed(vec![
        place(
            &grid,
            preset("phantom").unwrap(),
            Mat4::from_scale(Vec3::splat(0.6)),
        ),
        place(
            &amr,
            bands(),
            Mat4::from_translation(Vec3::new(0.4, 0.2, -0.3))
                * Mat4::from_rotation_y(0.6)
                * Mat4::from_scale(Vec3::splat(0.7)),
        ),
    ])
    .unwrap();
    let mut frames = Vec::new();
    for (name, mut r) in renderers() {
        for skipping in [true, false] {
            let settings = RenderSettings {
                skipping,
                ..RenderSettings::default()
            };
            frames.push((name, skipping, render(&mut r, &both, &settings)));
        }
    }
    let (gpu_on, gpu_off, cpu_on, cpu_off) =
        (&frames[0].2, &frames[1].2, &frames[2].2, &frames[3].2);
    for (what, a, b, min) in [
        ("gpu skipping on/off", gpu_on, gpu_off, 0.999),
        ("cpu skipping on/off", cpu_on, cpu_off, 0.999),
        ("gpu vs cpu", gpu_on, cpu_on, 0.999),
    ] {
        let s = ssim(a, b).unwrap();
        eprintln!(
            "{what}: SSIM {s:.5}, samples {} vs {}",
            a.samples, b.samples
        );
        assert!(s >= min, "{what}: SSIM {s}");
    }
    // Alone under a table that hides all but the highest values, rays
    // leap over most bricks: fewer samples, the same image.
    let peaks = TransferFunction::new(
        vec![Vec4::new(0.9, 0.6, 0.2, 1.0); 3],
        vec![0.0, 0.0, 1.0],
        (0.7, 1.0),
        0.1,
    )
    .unwrap();
    let alone = Scene::new(refined(64, 3, smooth_waves).unwrap(), peaks);
    for (name, mut r) in renderers() {
        let on = render(&mut r, &alone, &RenderSettings::default());
        let off = render(
            &mut r,
            &alone,
            &RenderSettings {
                skipping: false,
                ..RenderSettings::default()
            },
        );
        let s = ssim(&on, &off).unwrap();
        eprintln!(
            "{name} alone: skipping SSIM {s:.5}, samples {} of {}",
            on.samples, off.samples
        );
        assert!(s >= 0.999, "{name}: skipping changed the image: {s}");
        assert!(
            on.samples < off.samples / 2,
            "{name}: skipping took {} of {} samples",
            on.samples,
            off.samples
        );
    }
}
