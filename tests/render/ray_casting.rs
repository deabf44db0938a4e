//! The GPU ray caster held to the CPU reference, and the four cameras held
//! to each other, by SSIM over 8x8 windows.

use crate::common;

use anari_library_caveray::cave::Eye;
use anari_library_caveray::geometry::PrimaryRays;
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, ssim_map, CpuRenderer, FrameDesc, RenderSettings, Shading,
};
use anari_library_caveray::scene::Scene;
use common::render::{four_cameras, gpu, off_axis_wall, phantom};
use glam::{UVec2, Vec3};

const SHADINGS: [&str; 8] = [
    "none",
    "shadows",
    "ao",
    "shadows+ao",
    "directional:0",
    "directional:1",
    "directional:4",
    "directional:16",
];

#[test]
fn the_adapter_is_vulkan() {
    let gpu = gpu();
    println!("adapter: {:?}", gpu.adapter());
}

#[test]
fn gpu_matches_the_cpu_reference_in_every_shading_mode() {
    let mut gpu = gpu();
    let cpu = CpuRenderer::new();
    let scene = phantom(32);
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(64, 64);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let desc = FrameDesc::new(size);
    let mut plain = None;
    for mode in SHADINGS {
        let settings = RenderSettings {
            shading: mode.parse().unwrap(),
            ..Default::default()
        };
        let g = gpu.render(&scene, &rays, &settings, &desc).unwrap();
        let c = cpu.render(&scene, &rays, &settings, &desc).unwrap();
        let s = ssim(&g, &c).unwrap();
        println!("{mode:>15}: SSIM {s:.6}");
        assert!(s >= 0.99, "{mode}: GPU vs CPU SSIM {s}");
        // Shading must do something: every lit mode but N = 0 darkens.
        let plain = plain.get_or_insert_with(|| c.clone());
        let against_plain = ssim(&c, plain).unwrap();
        if matches!(mode, "none" | "directional:0") {
            assert_eq!(&c, plain, "{mode} must equal no shading");
        } else {
            assert!(
                against_plain < 0.999,
                "{mode} looks unshaded ({against_plain})"
            );
        }
    }
}

#[test]
fn gpu_matches_the_cpu_reference_for_every_camera_and_the_cameras_agree() {
    let mut gpu = gpu();
    let cpu = CpuRenderer::new();
    let scene = phantom(48);
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(96, 80);
    compare_cameras(
        &mut gpu,
        &cpu,
        &scene,
        four_cameras(&screen, eye, size),
        size,
    );
}

#[test]
fn an_off_axis_side_wall_of_the_cologne_cave_renders_alike_on_gpu_and_cpu() {
    let rig = common::rig("cologne_5wall");
    let head = rig.head_pose(None, None);
    let wall = rig.wall("left").unwrap();
    let view = rig.view(wall, Eye::Left, &head).unwrap();
    // In front of the left wall, to the viewer's left, so that wall sees
    // the volume at a steep angle.
    let scene = {
        let s = phantom(48);
        let volume = s.volumes()[0]
            .volume
            .structured()
            .unwrap()
            .clone()
            .placed(Vec3::new(-900.0, 300.0, 0.0), 800.0);
        let tf = (*s.volumes()[0].transfer_function)
            .clone()
            .with_unit_distance(400.0)
            .unwrap();
        Scene::new(volume, tf)
    };
    let size = UVec2::new(96, 96);
    let cameras = vec![
        ("offaxis", view.camera.ray_gen(size)),
        ("matrix", view.matrix_camera().unwrap().ray_gen(size)),
        ("pinhole", view.pinhole().unwrap().ray_gen(size)),
        (
            "from-matrices",
            view.pinhole_from_matrices().unwrap().camera.ray_gen(size),
        ),
    ];
    let mut gpu = gpu();
    let frames = compare_cameras(&mut gpu, &CpuRenderer::new(), &scene, cameras, size);
    let lit = frames[0].to_linear().iter().filter(|c| c.x > 0.02).count();
    assert!(lit > 100, "only {lit} lit pixels on the left wall");
}

/// Renders every camera on both renderers with shadows; returns the GPU frames.
fn compare_cameras(
    gpu: &mut anari_library_caveray::render::GpuRenderer,
    cpu: &CpuRenderer,
    scene: &Scene,
    cameras: Vec<(&str, anari_library_caveray::geometry::RayGen)>,
    size: UVec2,
) -> Vec<anari_library_caveray::render::Frame> {
    let settings = RenderSettings {
        shading: Shading::Shadows,
        light: Vec3::new(-0.5, 0.7, 0.5),
        ..Default::default()
    };
    let desc = FrameDesc::new(size);
    let mut frames = Vec::new();
    for (name, rays) in &cameras {
        let g = gpu.render(scene, rays, &settings, &desc).unwrap();
        let c = cpu.render(scene, rays, &settings, &desc).unwrap();
        let s = ssim(&g, &c).unwrap();
        println!("{name:>14}: GPU vs CPU SSIM {s:.6}");
        assert!(s >= 0.99, "{name}: GPU vs CPU SSIM {s}");
        frames.push(g);
    }
    for (i, (name, _)) in cameras.iter().enumerate().skip(1) {
        let map = ssim_map(&frames[0], &frames[i]).unwrap();
        println!(
            "{name:>14}: vs {} SSIM {:.6} (worst window {:.6})",
            cameras[0].0,
            map.mean(),
            map.min()
        );
        assert!(map.mean() >= 0.995, "{name} differs: SSIM {}", map.mean());
    }
    frames
}

/// `filter nearest`: both renderers take the nearest vertex (GPU equal to
/// the CPU reference), the picture differs from trilinear, and a two-voxel
/// volume shows the step where the vertices' halves meet.
#[test]
fn nearest_filter_is_nearest_on_both_renderers() {
    use anari_library_caveray::scene::{Filter, StructuredVolume, TransferFunction, Voxels};
    let mut gpu = gpu();
    let cpu = CpuRenderer::new();
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(64, 64);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let desc = FrameDesc::new(size);
    let settings = RenderSettings::default();
    let linear = phantom(16);
    let first = &linear.volumes()[0];
    let nearest = Scene::shared(
        std::sync::Arc::new(
            first
                .volume
                .structured()
                .unwrap()
                .clone()
                .with_filter(Filter::Nearest)
                .into(),
        ),
        first.transfer_function.clone(),
    );
    let g = gpu.render(&nearest, &rays, &settings, &desc).unwrap();
    let c = cpu.render(&nearest, &rays, &settings, &desc).unwrap();
    let s = ssim(&g, &c).unwrap();
    assert!(s >= 0.999, "nearest: GPU vs CPU SSIM {s}");
    let l = cpu.render(&linear, &rays, &settings, &desc).unwrap();
    let against_linear = ssim(&c, &l).unwrap();
    assert!(
        against_linear < 0.99,
        "nearest looks trilinear ({against_linear})"
    );

    // Vertices at x = -1 (value 0) and x = 1 (value 1); a slab seen along
    // z: nearest gives 0 left of x = 0.5 and 1 right of it, with no
    // ramp, where trilinear ramps.
    let step = StructuredVolume::new(
        glam::UVec3::new(2, 2, 2),
        Voxels::F32(vec![0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0].into()),
        Vec3::new(-1.0, -1.0, -0.5),
        Vec3::new(2.0, 2.0, 1.0),
    )
    .unwrap()
    .with_filter(Filter::Nearest);
    let white =
        TransferFunction::new(vec![glam::Vec4::ONE], vec![0.0, 1.0], (0.0, 1.0), 1.0).unwrap();
    let scene = Scene::new(step, white);
    let (screen, eye) = common::render::axis_camera(4.0, 1.5);
    let rays = anari_library_caveray::geometry::OffAxisCamera::new(screen, eye)
        .unwrap()
        .ray_gen(size);
    let settings = RenderSettings {
        background: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
        ..Default::default()
    };
    for (name, frame) in [
        ("gpu", gpu.render(&scene, &rays, &settings, &desc).unwrap()),
        ("cpu", cpu.render(&scene, &rays, &settings, &desc).unwrap()),
    ] {
        let px = frame.to_linear();
        let row = size.y / 2;
        let levels: Vec<f32> = (0..size.x)
            .map(|x| px[(row * size.x + x) as usize].x)
            .collect();
        // Inside the slab's x extent the level is 0 or the full opacity's
        // color, never in between.
        let distinct: Vec<f32> =
            levels
                .iter()
                .map(|v| (v * 100.0).round() / 100.0)
                .fold(Vec::new(), |mut seen, v| {
                    if !seen.contains(&v) {
                        seen.push(v);
                    }
                    seen
                });
        assert!(
            distinct.len() == 2,
            "{name}: levels along the row {distinct:?}"
        );
        let bright = levels.iter().position(|&v| v > 0.5).unwrap();
        assert!(
            (bright as i32 - size.x as i32 / 2).abs() <= 1,
            "{name}: the step is at column {bright}, not in the middle"
        );
    }
}

/// A background image (here ANARI's 1 x N gradient) behind an empty
/// volume: bottom row the first color, top row the last, blended in
/// between; the GPU equal to the CPU reference.
#[test]
fn background_gradients_on_both_renderers() {
    use anari_library_caveray::render::{BackgroundImage, ColorFormat};
    use anari_library_caveray::scene::TransferFunction;
    use glam::Vec4;
    let mut gpu = gpu();
    let cpu = CpuRenderer::new();
    let empty = Scene::shared(
        phantom(8).volumes()[0].volume.clone(),
        std::sync::Arc::new(
            TransferFunction::new(vec![Vec4::ONE], vec![0.0], (0.0, 1.0), 1.0).unwrap(),
        ),
    );
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(24, 40);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let (red, blue) = (Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 0.0, 1.0, 1.0));
    let gradient = BackgroundImage::new(UVec2::new(1, 2), vec![red, blue]).unwrap();
    let settings = RenderSettings {
        background_image: Some(std::sync::Arc::new(gradient)),
        ..Default::default()
    };
    let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
    let g = gpu.render(&empty, &rays, &settings, &desc).unwrap();
    let c = cpu.render(&empty, &rays, &settings, &desc).unwrap();
    for y in 0..size.y {
        for x in 0..size.x {
            let (a, b) = (g.pixel(x, y), c.pixel(x, y));
            assert!(
                (a - b).abs().max_element() < 1e-5,
                "({x},{y}): GPU {a} vs CPU {b}"
            );
        }
    }
    assert!((c.pixel(3, 0) - red).abs().max_element() < 1e-6);
    assert!((c.pixel(3, size.y - 1) - blue).abs().max_element() < 1e-6);
    let middle = c.pixel(3, size.y / 2);
    assert!(
        middle.x > 0.3 && middle.z > 0.3,
        "the middle blends: {middle}"
    );
    // Rows get bluer from bottom to top.
    assert!((1..size.y).all(|y| c.pixel(0, y).z >= c.pixel(0, y - 1).z));
}

#[test]
fn a_frame_cast_in_bands_is_whole_and_a_stop_ends_it_between_bands() {
    use anari_library_caveray::render::RenderError;
    use std::sync::atomic::AtomicBool;
    let mut gpu = gpu();
    let cpu = CpuRenderer::new();
    let scene = phantom(12);
    let (screen, eye) = off_axis_wall();
    // 520 x 520 is more than one band of 2^18 pixels: rows 0-503 and
    // 504-519.
    let size = UVec2::new(520, 520);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let settings = RenderSettings::default();
    let desc = FrameDesc::new(size).with_depth();
    let g = gpu.render(&scene, &rays, &settings, &desc).unwrap();
    let c = cpu.render(&scene, &rays, &settings, &desc).unwrap();
    let s = ssim(&g, &c).unwrap();
    assert!(s > 0.995, "banded GPU vs CPU SSIM {s}");
    // The last band's rows are there, not left at zero.
    let (gd, cd) = (g.depth.as_ref().unwrap(), c.depth.as_ref().unwrap());
    let last_rows = 504 * 520..520 * 520;
    assert_eq!(
        gd[last_rows.clone()]
            .iter()
            .filter(|d| d.is_finite())
            .count(),
        cd[last_rows].iter().filter(|d| d.is_finite()).count()
    );
    // Stopped before the first band: nothing is cast, and the renderer
    // carries on as before.
    let stop = AtomicBool::new(true);
    let e = gpu
        .render_until(&scene, &rays, &settings, &desc, &stop)
        .unwrap_err();
    assert_eq!(e, RenderError::Stopped);
    let again = gpu.render(&scene, &rays, &settings, &desc).unwrap();
    assert_eq!(again.color, g.color);
}

/// A volume kept in its stored type (16-bit integers read through a
/// file's rescale, 8-bit ones as UFIXED8) renders as the same values held
/// as f32 do: on the scalar path (which samples the stored numbers), the
/// packet path (a copy as f32) and the GPU.
#[test]
fn volumes_in_their_stored_type_render_as_their_values_do() {
    use anari_library_caveray::scene::{Scaling, StructuredVolume, Voxels};
    let mut gpu = gpu();
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(48, 48);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let desc = FrameDesc::new(size);
    let settings = RenderSettings::default();
    let as_f32 = phantom(24);
    let placed = &as_f32.volumes()[0];
    let reference = placed.volume.structured().unwrap();
    let n = reference.voxels().len();
    // The phantom's values in [0, 1], stored as int16 through a CT-like
    // rescale, and as 8-bit fixed point; the f32 twins hold exactly the
    // values the stored numbers stand for.
    let rescale = Scaling {
        slope: 1.0 / 2000.0,
        intercept: 0.5,
    };
    let int16: Vec<i16> = (0..n)
        .map(|i| ((reference.value(i) - 0.5) * 2000.0).round() as i16)
        .collect();
    let uint8: Vec<u8> = (0..n)
        .map(|i| (reference.value(i) * 255.0).round() as u8)
        .collect();
    let grid = |voxels: Voxels| {
        StructuredVolume::new(
            reference.dims(),
            voxels,
            reference.origin(),
            reference.spacing(),
        )
        .unwrap()
    };
    let stored = [
        (
            "int16 rescaled",
            grid(Voxels::I16(int16.into()))
                .with_scaling(rescale)
                .unwrap(),
        ),
        ("uint8 fixed point", grid(Voxels::U8(uint8.into()))),
    ];
    for (name, volume) in stored {
        let twin = grid(Voxels::F32(
            (0..n).map(|i| volume.value(i)).collect::<Vec<f32>>().into(),
        ));
        assert_eq!(volume.value_range(), twin.value_range(), "{name}");
        let scene = |v: StructuredVolume| {
            Scene::shared(
                std::sync::Arc::new(v.into()),
                placed.transfer_function.clone(),
            )
        };
        let (own, copy) = (scene(volume), scene(twin));
        let reference_cpu = CpuRenderer::reference();
        let expected = reference_cpu
            .render(&copy, &rays, &settings, &desc)
            .unwrap();
        for (path, frame) in [
            (
                "scalar, stored numbers",
                reference_cpu.render(&own, &rays, &settings, &desc).unwrap(),
            ),
            (
                "packets, f32 copy",
                CpuRenderer::new()
                    .render(&own, &rays, &settings, &desc)
                    .unwrap(),
            ),
            ("gpu", gpu.render(&own, &rays, &settings, &desc).unwrap()),
        ] {
            let s = ssim(&expected, &frame).unwrap();
            assert!(s >= 0.9999, "{name}, {path}: SSIM {s} against the f32 twin");
        }
    }
}
