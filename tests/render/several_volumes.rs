//! Several volumes in one scene, each with its own transfer function and
//! transform: composited per sample where they overlap, placed by any
//! affine transform, on the GPU and on the CPU reference alike.

use crate::common;

use std::sync::Arc;

use anari_library_caveray::data::{preset, shepp_logan, solid_box};
use anari_library_caveray::geometry::{OffAxisCamera, PrimaryRays};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, ColorFormat, CpuRenderer, FrameDesc, RenderSettings, Shading,
};
use anari_library_caveray::scene::{
    ObjectIds, PlacedVolume, Scene, SpatialField, StructuredVolume, TransferFunction, Voxels,
};
use common::render::{axis_camera, four_cameras, gpu, off_axis_wall, renderers};
use glam::{Mat4, UVec2, Vec3, Vec4};

fn colored(rgb: Vec3, opacity: f32, unit: f32) -> Arc<TransferFunction> {
    Arc::new(TransferFunction::new(vec![rgb.extend(1.0)], vec![opacity], (0.0, 1.0), unit).unwrap())
}

fn place(volume: &Arc<SpatialField>, tf: &Arc<TransferFunction>, m: Mat4) -> PlacedVolume {
    PlacedVolume {
        volume: Arc::clone(volume),
        transfer_function: Arc::clone(tf),
        transform: m,
        ids: ObjectIds::NONE,
    }
}

#[test]
fn overlapping_volumes_mix_per_sample_whatever_their_order() {
    // A red and a blue box of the same opacity: where both are, every
    // sample is half red, half blue, and the two absorb together. One box
    // composited after the other would let the front one dominate.
    let (a, unit) = (0.2f32, 0.5f32);
    let cube = Arc::new(solid_box(16).into());
    let red = colored(Vec3::X, a, unit);
    let blue = colored(Vec3::Z, a, unit);
    // Blue moved 1 along +x: x in [-1, 0) red only, [0, 1] both,
    // (1, 2] blue only.
    let shift = Mat4::from_translation(Vec3::X);
    let red_first = Scene::placed(vec![
        place(&cube, &red, Mat4::IDENTITY),
        place(&cube, &blue, shift),
    ])
    .unwrap();
    let blue_first = Scene::placed(vec![
        place(&cube, &blue, shift),
        place(&cube, &red, Mat4::IDENTITY),
    ])
    .unwrap();
    assert_eq!(
        red_first.bounds(),
        (Vec3::NEG_ONE, Vec3::new(2.0, 1.0, 1.0))
    );

    // A parallel-ish view down -z from far away, wide enough for x in
    // [-1.5, 2.5].
    let (screen, eye) = axis_camera(400.0, 2.0);
    let size = UVec2::new(41, 9);
    let camera = OffAxisCamera::new(screen, eye).unwrap();
    let rays = camera.ray_gen(size);
    let settings = RenderSettings {
        background: Vec4::ZERO,
        ..Default::default()
    };
    let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
    // Through 2 units of one box; of both.
    let one = 1.0 - (1.0 - f64::from(a)).powf(2.0 / f64::from(unit));
    let both = 1.0 - (1.0 - f64::from(a)).powf(2.0 * 2.0 / f64::from(unit));
    for (name, mut r) in renderers() {
        let f = r.render(&red_first, &rays, &settings, &desc).unwrap();
        let g = r.render(&blue_first, &rays, &settings, &desc).unwrap();
        let mut seen = [0; 3];
        for x in 0..size.x {
            let p = f.pixel(x, 4);
            let q = g.pixel(x, 4);
            assert!(
                (p - q).abs().max_element() < 1e-5,
                "{name}: column {x} depends on the order: {p} vs {q}"
            );
            let ray = camera.pixel_ray(x, 4, size);
            let wx = ray.origin.x + ray.direction.x * (ray.origin.z / -ray.direction.z);
            let alpha = f64::from(p.w);
            if (-0.9..-0.1).contains(&wx) {
                seen[0] += 1;
                assert!((alpha - one).abs() < 2e-3, "{name}: red only at {wx}: {p}");
                assert!(p.z == 0.0 && (p.x - p.w).abs() < 1e-5, "{name}: {p}");
            } else if (0.1..0.9).contains(&wx) {
                seen[1] += 1;
                assert!(
                    (alpha - both).abs() < 2e-3,
                    "{name}: both at {wx}: {p}, want {both}"
                );
                assert!(
                    (p.x - p.z).abs() < 1e-4 && (p.x + p.z - p.w).abs() < 1e-4,
                    "{name}: half red, half blue at {wx}: {p}"
                );
            } else if (1.1..1.9).contains(&wx) {
                seen[2] += 1;
                assert!((alpha - one).abs() < 2e-3, "{name}: blue only at {wx}: {p}");
                assert!(p.x == 0.0 && (p.z - p.w).abs() < 1e-5, "{name}: {p}");
            }
        }
        assert!(
            seen.iter().all(|&n| n >= 5),
            "{name}: columns seen {seen:?}"
        );
    }
}

/// `volume` (an n^3 cube on [-1, 1]^3) turned 90 degrees about +z, by
/// moving its voxels: world (X, Y, Z) is object (Y, -X, Z).
fn turned_by_hand(volume: &StructuredVolume) -> StructuredVolume {
    let n = volume.dims().x as usize;
    let turned: Vec<f32> = (0..n * n * n)
        .map(|w| {
            let (i, j, k) = (w % n, (w / n) % n, w / (n * n));
            volume.value(j + n * ((n - 1 - i) + n * k))
        })
        .collect();
    StructuredVolume::new(
        volume.dims(),
        Voxels::F32(turned.into()),
        volume.origin(),
        volume.spacing(),
    )
    .unwrap()
}

#[test]
fn a_rotated_volume_renders_as_its_grid_turned() {
    let volume = shepp_logan(20);
    let tf = Arc::new(preset("phantom").unwrap());
    let rotated = Scene::placed(vec![place(
        &Arc::new(volume.clone().into()),
        &tf,
        Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2),
    )])
    .unwrap();
    let by_hand = Scene::shared(Arc::new(turned_by_hand(&volume).into()), Arc::clone(&tf));
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(32, 32);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let desc = FrameDesc::new(size);
    for (name, mut r) in renderers() {
        for shading in [Shading::None, Shading::Shadows] {
            let settings = RenderSettings {
                shading,
                ..Default::default()
            };
            let a = r.render(&rotated, &rays, &settings, &desc).unwrap();
            let b = r.render(&by_hand, &rays, &settings, &desc).unwrap();
            let s = ssim(&a, &b).unwrap();
            assert!(s > 0.999, "{name} {shading}: SSIM {s}");
        }
        // And it is not the unrotated volume.
        let settings = RenderSettings::default();
        let a = r.render(&rotated, &rays, &settings, &desc).unwrap();
        let plain = Scene::shared(Arc::new(volume.clone().into()), Arc::clone(&tf));
        let c = r.render(&plain, &rays, &settings, &desc).unwrap();
        assert!(
            ssim(&a, &c).unwrap() < 0.95,
            "{name}: rotation had no effect"
        );
    }
}

#[test]
fn overlapping_rotated_volumes_on_the_gpu_match_the_cpu_reference() {
    let phantom = Arc::new(shepp_logan(24).into());
    let cube = Arc::new(solid_box(8).into());
    let scene = Scene::placed(vec![
        place(
            &phantom,
            &Arc::new(preset("phantom").unwrap()),
            Mat4::from_rotation_y(0.5) * Mat4::from_scale(Vec3::new(1.0, 0.8, 1.2)),
        ),
        place(
            &cube,
            &colored(Vec3::new(0.2, 0.9, 0.3), 0.15, 1.0),
            Mat4::from_translation(Vec3::new(0.4, 0.3, 0.2))
                * Mat4::from_rotation_x(0.7)
                * Mat4::from_scale(Vec3::splat(0.5)),
        ),
        place(
            &phantom,
            &Arc::new(preset("mri").unwrap()),
            Mat4::from_translation(Vec3::new(-0.6, -0.5, 0.0)) * Mat4::from_scale(Vec3::splat(0.4)),
        ),
    ])
    .unwrap();
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(40, 40);
    let mut gpu = gpu();
    let cpu = CpuRenderer::new();
    for (camera, rays) in four_cameras(&screen, eye, size).into_iter().take(2) {
        for shading in [Shading::None, Shading::ShadowsAo] {
            let settings = RenderSettings {
                shading,
                ..Default::default()
            };
            let desc = FrameDesc::new(size).with_depth();
            let g = gpu.render(&scene, &rays, &settings, &desc).unwrap();
            let c = cpu.render(&scene, &rays, &settings, &desc).unwrap();
            let s = ssim(&g, &c).unwrap();
            assert!(s > 0.995, "{camera} {shading}: GPU vs CPU SSIM {s}");
            // Each volume's samples are counted; the same on both.
            let ratio = g.samples as f64 / c.samples as f64;
            assert!((ratio - 1.0).abs() < 0.01, "{camera}: samples {ratio}");
        }
    }
    // Three volumes on two grids (one Arc placed twice): two volume
    // uploads and three tables, made once for all four renders.
    let u = gpu.uploads();
    assert_eq!((u.volumes, u.transfer_functions), (2, 3));
}
