//! Images whose right answer is known without a renderer, checked on the
//! GPU and on the CPU reference alike.

use crate::common;

use anari_library_caveray::data::{preset, shepp_logan, solid_box};
use anari_library_caveray::geometry::{OffAxisCamera, PrimaryRays};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, ColorData, ColorFormat, CpuRenderer, Frame, FrameDesc, RenderSettings, Renderer, Shading,
};
use anari_library_caveray::scene::{Scene, StructuredVolume, TransferFunction, Voxels};
use common::render::{axis_camera, four_cameras, gpu, off_axis_wall, renderers};
use glam::{DVec3, UVec2, UVec3, Vec3, Vec4};

fn constant_tf(opacity: f32, unit_distance: f32) -> TransferFunction {
    TransferFunction::new(vec![Vec4::ONE], vec![opacity], (0.0, 1.0), unit_distance).unwrap()
}

const SHADINGS: [Shading; 5] = [
    Shading::None,
    Shading::Shadows,
    Shading::Ao,
    Shading::ShadowsAo,
    Shading::Directional(4),
];

#[test]
fn an_empty_volume_gives_exactly_the_background() {
    // Data that is there but fully transparent, in every shading mode.
    let scene = Scene::new(shepp_logan(24), constant_tf(0.0, 1.0));
    let background = Vec4::new(0.2, 0.4, 0.6, 1.0);
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(24, 20);
    let rays = four_cameras(&screen, eye, size)[0].1;
    for (name, mut r) in renderers() {
        for shading in SHADINGS {
            let settings = RenderSettings {
                background,
                shading,
                ..Default::default()
            };
            for format in [
                ColorFormat::Rgba8,
                ColorFormat::Srgba8,
                ColorFormat::Rgba32F,
            ] {
                let desc = FrameDesc::new(size).with_color(format).with_depth();
                let f = r.render(&scene, &rays, &settings, &desc).unwrap();
                let expected = match format {
                    ColorFormat::Rgba32F => {
                        ColorData::Rgba32F(background.to_array().repeat(desc.pixels()))
                    }
                    ColorFormat::Rgba8 => {
                        ColorData::Rgba8([51u8, 102, 153, 255].repeat(desc.pixels()))
                    }
                    // sRGB of 0.2, 0.4, 0.6: 124, 170, 203.
                    ColorFormat::Srgba8 => {
                        ColorData::Srgba8([124u8, 170, 203, 255].repeat(desc.pixels()))
                    }
                };
                assert_eq!(f.color, expected, "{name} {shading} {format:?}");
                let depth = f.depth.unwrap();
                assert!(depth.iter().all(|d| d.is_infinite()), "{name}: depth");
            }
        }
    }
}

/// Length of the chord of the ray through [-1, 1]^3, from t >= 0 on.
fn chord(origin: DVec3, dir: DVec3) -> f64 {
    let inv = dir.recip();
    let ta = (DVec3::NEG_ONE - origin) * inv;
    let tb = (DVec3::ONE - origin) * inv;
    let t0 = ta.min(tb).max_element().max(0.0);
    let t1 = ta.max(tb).min_element();
    (t1 - t0).max(0.0)
}

#[test]
fn a_solid_box_has_the_analytic_transmittance() {
    let (a, unit) = (0.3f32, 0.7f32);
    let scene = Scene::new(solid_box(16), constant_tf(a, unit));
    let (screen, eye) = axis_camera(4.0, 1.5);
    let size = UVec2::new(33, 33);
    let camera = OffAxisCamera::new(screen, eye).unwrap();
    let rays = camera.ray_gen(size);
    let settings = RenderSettings {
        background: Vec4::ZERO,
        ..Default::default()
    };
    let desc = FrameDesc::new(size)
        .with_color(ColorFormat::Rgba32F)
        .with_depth();
    let expected = |len: f64| 1.0 - (1.0 - f64::from(a)).powf(len / f64::from(unit));
    for (name, mut r) in renderers() {
        let f = r.render(&scene, &rays, &settings, &desc).unwrap();
        // Through the centre: 2 units of box.
        let centre = f.pixel(16, 16);
        let want = expected(2.0);
        assert!(
            (f64::from(centre.w) - want).abs() < 1e-3,
            "{name}: centre alpha {} vs {want}",
            centre.w
        );
        assert!(
            (centre.x - centre.w).abs() < 1e-6,
            "{name}: white, premultiplied"
        );
        // Every other pixel, by its own chord.
        let mut worst = 0.0f64;
        for y in 0..size.y {
            for x in 0..size.x {
                let ray = camera.pixel_ray(x, y, size);
                let want = expected(chord(ray.origin, ray.direction));
                worst = worst.max((f64::from(f.pixel(x, y).w) - want).abs());
            }
        }
        println!("{name}: largest alpha error {worst:.2e}");
        assert!(worst < 1e-3, "{name}: alpha off by {worst}");
        // Depth is where the accumulated opacity first reaches the
        // threshold (0.5 by default): after k samples of opacity a_s each
        // (steps of 1/15 from the entry at 3, sampled at their middles).
        let step = 1.0 / 15.0;
        let a_s = 1.0 - (1.0 - f64::from(a)).powf(step / f64::from(unit));
        let k = ((1.0f64 - 0.5).ln() / (1.0 - a_s).ln()).ceil();
        let depth = f.depth.as_ref().unwrap()[16 * 33 + 16];
        let want = 3.0 + (k - 0.5) * step;
        assert!(
            (f64::from(depth) - want).abs() < 1e-4,
            "{name}: depth {depth}, want {want} ({k} samples)"
        );
        // With threshold 0, the first sample: half a step past the entry.
        let first = RenderSettings {
            depth_threshold: 0.0,
            ..settings.clone()
        };
        let f = r.render(&scene, &rays, &first, &desc).unwrap();
        let depth = f.depth.as_ref().unwrap()[16 * 33 + 16];
        assert!(
            (depth - (3.0 + 1.0 / 30.0)).abs() < 1e-4,
            "{name}: first-sample depth {depth}"
        );
    }
}

fn max_difference(a: &Frame, b: &Frame) -> f32 {
    a.to_linear()
        .iter()
        .zip(b.to_linear())
        .map(|(p, q)| (*p - q).abs().max_element())
        .fold(0.0, f32::max)
}

#[test]
fn early_termination_does_not_change_an_opaque_image() {
    let tf = preset("grey").unwrap().with_unit_distance(0.01).unwrap();
    let scene = Scene::new(shepp_logan(32), tf);
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(48, 48);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
    for (name, mut r) in renderers() {
        for shading in [Shading::None, Shading::Shadows] {
            let on = RenderSettings {
                shading,
                ..Default::default()
            };
            let off = RenderSettings {
                termination: 2.0,
                ..on.clone()
            };
            let a = r.render(&scene, &rays, &on, &desc).unwrap();
            let b = r.render(&scene, &rays, &off, &desc).unwrap();
            let diff = max_difference(&a, &b);
            println!(
                "{name} {shading}: max difference {diff:.2e}, samples {} with ERT vs {} without",
                a.samples, b.samples
            );
            // What is left after opacity 0.99 can change a pixel by 1%.
            assert!(
                diff <= 0.01,
                "{name} {shading}: ERT changed a pixel by {diff}"
            );
            assert!(ssim(&a, &b).unwrap() > 0.999);
            // Rays through air take every step either way, so expect a
            // clear saving rather than a fixed ratio.
            assert!(
                a.samples * 10 < b.samples * 9,
                "{name}: early termination saved too little ({} vs {})",
                a.samples,
                b.samples
            );
        }
    }
}

#[test]
fn both_renderers_take_the_same_samples() {
    let scene = common::render::phantom(24);
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(32, 32);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let mut gpu = gpu();
    let cpu = CpuRenderer::new();
    for shading in SHADINGS {
        let settings = RenderSettings {
            shading,
            ..Default::default()
        };
        let g = gpu
            .render(&scene, &rays, &settings, &FrameDesc::new(size))
            .unwrap();
        let c = cpu
            .render(&scene, &rays, &settings, &FrameDesc::new(size))
            .unwrap();
        let rel = (g.samples as f64 - c.samples as f64).abs() / c.samples as f64;
        assert!(
            rel < 1e-3,
            "{shading}: GPU {} vs CPU {} samples",
            g.samples,
            c.samples
        );
        assert!(
            c.samples > u64::from(size.x * size.y),
            "{shading}: too few samples"
        );
    }
}

#[test]
fn color_formats_encode_the_same_image() {
    let scene = common::render::phantom(24);
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(32, 32);
    let rays = four_cameras(&screen, eye, size)[0].1;
    for (name, mut r) in renderers() {
        let settings = RenderSettings::default();
        let render = |r: &mut Renderer, format| {
            r.render(
                &scene,
                &rays,
                &settings,
                &FrameDesc::new(size).with_color(format),
            )
            .unwrap()
        };
        let linear = render(&mut r, ColorFormat::Rgba32F);
        for format in [ColorFormat::Rgba8, ColorFormat::Srgba8] {
            let f = render(&mut r, format);
            // 8-bit quantisation: half a step in the stored encoding.
            let diff = max_difference(&f, &linear);
            assert!(diff < 0.01, "{name} {format:?}: off by {diff}");
        }
    }
}

#[test]
fn the_gpu_uploads_a_scene_once_and_again_only_when_it_changes() {
    let mut gpu = gpu();
    let scene = common::render::phantom(16);
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(16, 16);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let settings = RenderSettings::default();
    for _ in 0..3 {
        gpu.render(&scene, &rays, &settings, &FrameDesc::new(size))
            .unwrap();
    }
    let u = gpu.uploads();
    assert_eq!((u.volumes, u.transfer_functions), (1, 1));
    // A new transfer function re-uploads the table only.
    let recolored = Scene::shared(
        scene.volumes()[0].volume.clone(),
        std::sync::Arc::new(preset("mri").unwrap()),
    );
    gpu.render(&recolored, &rays, &settings, &FrameDesc::new(size))
        .unwrap();
    let u = gpu.uploads();
    assert_eq!((u.volumes, u.transfer_functions), (1, 2));
    // A new volume (u8 this time) re-uploads the volume only.
    let dims = UVec3::splat(8);
    let bytes: Vec<u8> = (0..512u32).map(|i| (i % 251) as u8).collect();
    let volume = StructuredVolume::new(
        dims,
        Voxels::U8(bytes.into()),
        Vec3::NEG_ONE,
        Vec3::splat(2.0 / 7.0),
    )
    .unwrap();
    let other = Scene::shared(
        std::sync::Arc::new(volume.into()),
        recolored.volumes()[0].transfer_function.clone(),
    );
    let g = gpu
        .render(&other, &rays, &settings, &FrameDesc::new(size))
        .unwrap();
    let u = gpu.uploads();
    assert_eq!((u.volumes, u.transfer_functions), (2, 2));
    // And the new upload is what gets rendered.
    let c = CpuRenderer::new()
        .render(&other, &rays, &settings, &FrameDesc::new(size))
        .unwrap();
    assert!(ssim(&g, &c).unwrap() > 0.99);
}

#[test]
fn the_cpu_reference_notices_a_new_volume_or_transfer_function() {
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(16, 16);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let settings = RenderSettings::default();
    let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
    let first = common::render::phantom(16);
    let recolored = Scene::shared(
        first.volumes()[0].volume.clone(),
        std::sync::Arc::new(preset("mri").unwrap()),
    );
    let other = Scene::new(
        shepp_logan(12),
        (*recolored.volumes()[0].transfer_function).clone(),
    );
    // One renderer across scene changes against a fresh one per scene.
    let reused = CpuRenderer::new();
    for scene in [&first, &recolored, &other, &first] {
        let a = reused.render(scene, &rays, &settings, &desc).unwrap();
        let b = CpuRenderer::new()
            .render(scene, &rays, &settings, &desc)
            .unwrap();
        assert_eq!(a, b);
    }
    let a = reused.render(&first, &rays, &settings, &desc).unwrap();
    let b = reused.render(&recolored, &rays, &settings, &desc).unwrap();
    assert_ne!(a, b, "a new transfer function must change the image");
}

/// A 3 x 3 orthographic view at z = 4 looking down -z on the [-1, 1]^3
/// box: pixels within +-1 see 2 units of box, the rest none.
fn box_from_above() -> anari_library_caveray::geometry::OrthographicCamera {
    use anari_library_caveray::geometry::{ImageRegion, OrthographicCamera};
    OrthographicCamera::new(
        DVec3::new(0.0, 0.0, 4.0),
        DVec3::NEG_Z,
        DVec3::Y,
        3.0,
        1.0,
        ImageRegion::FULL,
    )
    .unwrap()
}

/// The orthographic camera's parallel rays cross the [-1, 1]^3 box with
/// the same chord everywhere inside its footprint; near and far clip the
/// rays, on both renderers.
#[test]
fn orthographic_rays_and_clip_ranges() {
    let (a, unit) = (0.3f32, 0.7f32);
    let scene = Scene::new(solid_box(16), constant_tf(a, unit));
    let size = UVec2::new(32, 32);
    let camera = box_from_above();
    let rays = camera.ray_gen(size);
    let settings = RenderSettings {
        background: Vec4::ZERO,
        ..Default::default()
    };
    let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
    let through = |len: f64| 1.0 - (1.0 - f64::from(a)).powf(len / f64::from(unit));
    for (name, mut r) in renderers() {
        let f = r.render(&scene, &rays, &settings, &desc).unwrap();
        for y in 0..size.y {
            for x in 0..size.x {
                let ray = camera.pixel_ray(x, y, size);
                let inside = ray.origin.x.abs() < 1.0 && ray.origin.y.abs() < 1.0;
                let want = if inside { through(2.0) } else { 0.0 };
                let got = f64::from(f.pixel(x, y).w);
                assert!(
                    (got - want).abs() < 1e-3,
                    "{name}: pixel {x},{y} alpha {got} vs {want}"
                );
            }
        }
        // Near at 3.5 (half a unit into the box), far at 4.5: one unit.
        let clipped = r
            .render(&scene, &rays.clipped(3.5, 4.5), &settings, &desc)
            .unwrap();
        let got = f64::from(clipped.pixel(16, 16).w);
        assert!(
            (got - through(1.0)).abs() < 2e-2,
            "{name}: clipped alpha {got}"
        );
        // Far before the box: nothing.
        let before = r
            .render(&scene, &rays.clipped(0.0, 2.5), &settings, &desc)
            .unwrap();
        assert_eq!(before.pixel(16, 16).w, 0.0, "{name}: far before the box");
    }
}

/// Depth is the distance from the eye for every camera: the matrix
/// camera's rays start on the near plane, yet its depth equals the
/// off-axis camera's for the same wall and eye.
#[test]
fn depth_is_measured_from_the_eye_for_every_camera() {
    let scene = Scene::new(solid_box(16), constant_tf(0.3, 0.7));
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(40, 40);
    let cameras = four_cameras(&screen, eye, size);
    let desc = FrameDesc::new(size).with_depth();
    for (name, mut r) in renderers() {
        let depths: Vec<(&str, Vec<f32>)> = cameras
            .iter()
            .map(|(camera, rays)| {
                let f = r
                    .render(&scene, rays, &RenderSettings::default(), &desc)
                    .unwrap();
                (*camera, f.depth.unwrap())
            })
            .collect();
        let (_, reference) = &depths[0];
        let hits = reference.iter().filter(|d| d.is_finite()).count();
        assert!(hits > 100, "{name}: only {hits} pixels hit the box");
        for (camera, d) in &depths[1..] {
            let worst = reference
                .iter()
                .zip(d)
                .filter(|(a, _)| a.is_finite())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            assert!(
                worst < 2e-3,
                "{name} {camera}: depth differs by {worst} from the off-axis camera's"
            );
        }
    }
}

/// Clip planes (n, d) keep dot(n, p) < d along every primary ray: x < 0
/// leaves the left half of the box, and with x > 0.5 as well nothing.
#[test]
fn clip_planes_cut_the_rays_on_both_renderers() {
    use anari_library_caveray::render::ClipPlanes;
    let (a, unit) = (0.3f32, 0.7f32);
    let scene = Scene::new(solid_box(16), constant_tf(a, unit));
    let size = UVec2::new(32, 32);
    let camera = box_from_above();
    let rays = camera.ray_gen(size);
    let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
    let with = |planes: &[Vec4]| RenderSettings {
        background: Vec4::ZERO,
        clip_planes: ClipPlanes::new(planes).unwrap(),
        ..Default::default()
    };
    let full = 1.0 - (1.0 - f64::from(a)).powf(2.0 / f64::from(unit));
    for (name, mut r) in renderers() {
        let f = r
            .render(
                &scene,
                &rays,
                &with(&[Vec4::new(1.0, 0.0, 0.0, 0.0)]),
                &desc,
            )
            .unwrap();
        for y in 0..size.y {
            for x in 0..size.x {
                let o = camera.pixel_ray(x, y, size).origin;
                let inside = o.x.abs() < 1.0 && o.y.abs() < 1.0;
                let want = if inside && o.x < 0.0 { full } else { 0.0 };
                let got = f64::from(f.pixel(x, y).w);
                assert!(
                    (got - want).abs() < 1e-3,
                    "{name}: pixel {x},{y} alpha {got} vs {want}"
                );
            }
        }
        // A plane the rays run along keeps all or nothing; two planes that
        // leave no space keep nothing.
        let none = r
            .render(
                &scene,
                &rays,
                &with(&[
                    Vec4::new(1.0, 0.0, 0.0, 0.0),
                    Vec4::new(-1.0, 0.0, 0.0, -0.5),
                ]),
                &desc,
            )
            .unwrap();
        assert!(
            (0..size.x * size.y).all(|i| none.pixel(i % size.x, i / size.x).w == 0.0),
            "{name}"
        );
        // More than eight planes are refused.
        assert!(ClipPlanes::new(&[Vec4::X; 9]).is_none());
    }
}
