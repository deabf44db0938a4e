//! Bad input to the renderers: clear errors, no panic, and the renderer
//! keeps working afterwards.

use crate::common;

use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, CpuRenderer, FrameDesc, RenderError, RenderSettings, Shading,
};
use anari_library_caveray::scene::{Scene, StructuredVolume, Voxels};
use common::render::{four_cameras, gpu, off_axis_wall, phantom, renderers};
use glam::{UVec2, UVec3, Vec3, Vec4};

#[test]
fn a_volume_longer_than_the_adapters_textures_is_paged_and_renders_as_on_the_cpu() {
    let mut gpu = gpu();
    let max = gpu.limits().max_texture_dimension_3d;
    let dims = UVec3::new(max + 1, 5, 6);
    let n = (dims.x * dims.y * dims.z) as usize;
    let voxels = Voxels::U8(
        (0..n)
            .map(|i| (i * 37 % 251) as u8)
            .collect::<Vec<u8>>()
            .into(),
    );
    // A unit cube in the world, however many voxels span each axis.
    let spacing = 1.0 / (dims - UVec3::ONE).as_vec3();
    let long = StructuredVolume::new(dims, voxels, Vec3::splat(-0.5), spacing).unwrap();
    let good = phantom(16);
    let scene = Scene::new(long, (*good.volumes()[0].transfer_function).clone());
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(24, 16);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let settings = RenderSettings::default();
    let desc = FrameDesc::new(size);
    let frame = gpu.render(&scene, &rays, &settings, &desc).unwrap();
    let expected = CpuRenderer::reference()
        .render(&scene, &rays, &settings, &desc)
        .unwrap();
    let s = ssim(&frame, &expected).unwrap();
    assert!(s >= 0.9999, "SSIM {s} against the CPU");
    assert!(frame.samples > 0);
    // Bricks of 63 voxels and their aprons along x, y and z whole, at
    // every level of the chain (x halves until one brick holds it), and
    // the page table: a word per level and per brick.
    let mut bricks = Vec::new();
    let mut x = dims.x;
    loop {
        bricks.push(u64::from(x.div_ceil(63)));
        if x <= 63 {
            break;
        }
        x = x.div_ceil(2);
    }
    let count: u64 = bricks.iter().sum();
    let table = 4 * (bricks.len() as u64 + count);
    assert_eq!(gpu.volume_bytes(), count * 64 * 5 * 6 + table);
}

#[test]
fn a_frame_larger_than_the_adapter_allows_is_refused_up_front() {
    let mut gpu = gpu();
    let groups = gpu.limits().max_compute_workgroups_per_dimension;
    let size = UVec2::new(8 * groups + 8, 1);
    let scene = phantom(8);
    let (screen, eye) = off_axis_wall();
    let rays = four_cameras(&screen, eye, size)[0].1;
    let err = gpu
        .render(
            &scene,
            &rays,
            &RenderSettings::default(),
            &FrameDesc::new(size),
        )
        .unwrap_err();
    assert!(
        err.to_string()
            .contains(&format!("frame of {}x1 is too large", size.x)),
        "{err}"
    );
}

#[test]
fn bad_settings_and_frames_are_errors_on_both_renderers() {
    let scene = phantom(8);
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(8, 8);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let ok = RenderSettings::default();
    let cases: Vec<(RenderSettings, FrameDesc, &str)> = vec![
        (
            RenderSettings {
                step_factor: 0.0,
                ..ok.clone()
            },
            FrameDesc::new(size),
            "step factor must be in [0.015625, 64], got 0.0",
        ),
        (
            RenderSettings {
                step_factor: 1e-30,
                ..ok.clone()
            },
            FrameDesc::new(size),
            "step factor must be in [0.015625, 64], got 1e-30",
        ),
        (
            RenderSettings {
                step_factor: f32::INFINITY,
                ..ok.clone()
            },
            FrameDesc::new(size),
            "got inf",
        ),
        (
            RenderSettings {
                background: Vec4::new(f32::NAN, 0.0, 0.0, 1.0),
                ..ok.clone()
            },
            FrameDesc::new(size),
            "background must be four numbers in [0, 1]",
        ),
        (
            RenderSettings {
                termination: f32::NAN,
                ..ok.clone()
            },
            FrameDesc::new(size),
            "termination threshold must be finite and positive",
        ),
        (
            RenderSettings {
                light: Vec3::ZERO,
                ..ok.clone()
            },
            FrameDesc::new(size),
            "light direction must be a finite non-zero vector",
        ),
        (
            RenderSettings {
                shading: Shading::Directional(65),
                ..ok.clone()
            },
            FrameDesc::new(size),
            "directional shading takes at most 64 directions, got 65",
        ),
        (
            ok.clone(),
            FrameDesc::new(UVec2::new(0, 4)),
            "frame size must be at least 1x1, got 0x4",
        ),
        // Refused before anything is allocated: allocating it would abort
        // the host ("memory allocation of 160000000000 bytes failed").
        (
            ok.clone(),
            FrameDesc::new(UVec2::new(100_000, 100_000)),
            "a frame of 100000x100000 is 10000000000 pixels; caveray renders up to 268435456 (16384 x 16384) per frame",
        ),
    ];
    for (name, mut r) in renderers() {
        for (settings, desc, message) in &cases {
            let err = r.render(&scene, &rays, settings, desc).unwrap_err();
            assert!(matches!(err, RenderError::Settings(_)), "{name}: {err:?}");
            assert!(err.to_string().contains(message), "{name}: {err}");
        }
        let f = r.render(&scene, &rays, &ok, &FrameDesc::new(size)).unwrap();
        assert_eq!(f.size, size, "{name} still renders");
    }
}

#[test]
fn shading_modes_parse_and_bad_ones_list_the_choices() {
    for (text, mode) in [
        ("none", Shading::None),
        ("shadows", Shading::Shadows),
        ("ao", Shading::Ao),
        ("shadows+ao", Shading::ShadowsAo),
        ("directional:16", Shading::Directional(16)),
    ] {
        assert_eq!(text.parse::<Shading>().unwrap(), mode);
        assert_eq!(mode.to_string(), text);
    }
    assert_eq!(Shading::Directional(16).extra_samples(), 64);
    for bad in ["phong", "directional:", "directional:65", "directional:-1"] {
        let err = bad.parse::<Shading>().unwrap_err().to_string();
        assert!(
            err.contains(&format!("unknown shading mode \"{bad}\""))
                && err.contains("none, shadows, ao, shadows+ao or directional:N"),
            "{err}"
        );
    }
}

#[test]
fn ssim_refuses_frames_it_cannot_compare() {
    let scene = phantom(8);
    let (screen, eye) = off_axis_wall();
    let cpu = CpuRenderer::new();
    let render = |size: UVec2| {
        let rays = four_cameras(&screen, eye, size)[0].1;
        cpu.render(
            &scene,
            &rays,
            &RenderSettings::default(),
            &FrameDesc::new(size),
        )
        .unwrap()
    };
    let (a, b, tiny) = (
        render(UVec2::new(16, 16)),
        render(UVec2::new(16, 12)),
        render(UVec2::new(4, 4)),
    );
    assert!(ssim(&a, &b)
        .unwrap_err()
        .to_string()
        .contains("same size, got 16x16 and 16x12"));
    assert!(ssim(&tiny, &tiny)
        .unwrap_err()
        .to_string()
        .contains("at least 8x8, got 4x4"));
    assert_eq!(ssim(&a, &a).unwrap(), 1.0);
}

#[test]
fn rays_through_a_scene_too_fine_to_cross_stop_at_the_cap_with_a_warning() {
    // A speck (cells of 1e-6) beside the phantom sets the step for both:
    // crossing the scene would take ~7 million steps per ray. Each ray
    // stops at MAX_STEPS_PER_RAY, and the warning says why.
    use anari_library_caveray::geometry::RayGen;
    use anari_library_caveray::render::{march_warning, MAX_STEPS_PER_RAY};
    use anari_library_caveray::scene::{PlacedVolume, Scene};
    use glam::Mat4;
    let phantom = phantom(8).volumes()[0].clone();
    let speck = PlacedVolume {
        transform: Mat4::from_scale(Vec3::splat(1e-6)),
        ..phantom.clone()
    };
    let scene = Scene::placed(vec![phantom, speck]).unwrap();
    let ok = RenderSettings::default();
    let warning = march_warning(&scene, &ok).expect("the cap bites");
    assert!(
        warning.starts_with(&format!("rays are cut at {MAX_STEPS_PER_RAY} steps")),
        "{warning}"
    );
    // One ray along the z axis, through both.
    let rays = RayGen {
        origin: Vec3::new(0.01, 0.02, 5.0),
        direction: Vec3::NEG_Z,
        ..RayGen::default()
    };
    for (name, mut r) in renderers() {
        let f = r
            .render(&scene, &rays, &ok, &FrameDesc::new(UVec2::ONE))
            .unwrap();
        assert!(
            f.samples > 0 && f.samples <= 2 * u64::from(MAX_STEPS_PER_RAY),
            "{name}: {} samples",
            f.samples
        );
    }
}
