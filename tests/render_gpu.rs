//! The GPU ray caster held to the CPU reference, and the four cameras held
//! to each other, by SSIM over 8x8 windows.

mod common;

use anari_library_caveray::cave::Eye;
use anari_library_caveray::geometry::PrimaryRays;
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
        let volume = (*s.volume)
            .clone()
            .placed(Vec3::new(-900.0, 300.0, 0.0), 800.0);
        let tf = (*s.transfer_function)
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
