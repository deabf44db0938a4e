//! Volumes paged on the GPU (bricks with a one-voxel apron in a pool
//! texture, read through a page table), every brick resident, render as
//! the same volume in one texture does, and as the CPU reference renders
//! it; budgets too small for a brick are refused before anything is
//! allocated.

use crate::common;

use std::sync::Arc;

use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{ssim, CpuRenderer, FrameDesc, RenderSettings, Sampling};
use anari_library_caveray::scene::{Filter, Scaling, Scene, StructuredVolume, Voxels};
use common::render::{four_cameras, gpu, off_axis_wall};
use glam::UVec2;

/// The phantom stored as uint16 through a rescale, as a scanner would
/// write it.
fn as_uint16(volume: &StructuredVolume) -> StructuredVolume {
    let n = volume.voxels().len();
    let stored: Vec<u16> = (0..n)
        .map(|i| (volume.value(i) * 4000.0).round() as u16)
        .collect();
    StructuredVolume::new(
        volume.dims(),
        Voxels::U16(stored.into()),
        volume.origin(),
        volume.spacing(),
    )
    .unwrap()
    .with_scaling(Scaling {
        slope: 1.0 / 4000.0,
        intercept: 0.0,
    })
    .unwrap()
}

#[test]
fn a_bricked_volume_renders_as_a_whole_one() {
    let mut gpu = gpu();
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(56, 48);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let desc = FrameDesc::new(size);
    let tf = Arc::new(preset("phantom").unwrap());
    // 30 voxels a side: bricks of 7 leave a partial brick at every far
    // face, and every trilinear cell on a brick's last voxel reads the
    // apron.
    let f32_phantom = shepp_logan(30);
    let scenes = [
        (
            "float32",
            Scene::shared(Arc::new(f32_phantom.clone().into()), Arc::clone(&tf)),
        ),
        (
            "uint16",
            Scene::shared(Arc::new(as_uint16(&f32_phantom).into()), Arc::clone(&tf)),
        ),
        (
            "nearest",
            Scene::shared(
                Arc::new(f32_phantom.with_filter(Filter::Nearest).into()),
                Arc::clone(&tf),
            ),
        ),
    ];
    let exact = |shading: &str| RenderSettings {
        shading: shading.parse().unwrap(),
        ..Default::default()
    };
    let cpu = CpuRenderer::reference();
    for (name, scene) in &scenes {
        let voxels = scene.volumes()[0]
            .volume
            .dims()
            .as_u64vec3()
            .element_product();
        for shading in ["none", "directional:1"] {
            let settings = exact(shading);
            let expected = cpu.render(scene, &rays, &settings, &desc).unwrap();
            gpu.brick_every_volume(None);
            let whole = gpu.render(scene, &rays, &settings, &desc).unwrap();
            gpu.brick_every_volume(Some(8));
            let bricked = gpu.render(scene, &rays, &settings, &desc).unwrap();
            // Bricks of 7 voxels plus the apron: 5 x 5 x 5 bricks of 8^3
            // texels, in an atlas of whole layers of bricks.
            assert!(
                gpu.volume_bytes() >= 125 * 512,
                "{name}: {}",
                gpu.volume_bytes()
            );
            assert!(gpu.volume_bytes() > voxels, "{name}");
            let against_whole = ssim(&bricked, &whole).unwrap();
            let against_cpu = ssim(&bricked, &expected).unwrap();
            println!("{name} {shading}: SSIM {against_whole:.6} to one texture, {against_cpu:.6} to the CPU");
            assert!(
                against_whole >= 0.9999,
                "{name} {shading}: {against_whole} against one texture"
            );
            assert!(
                against_cpu >= 0.9999,
                "{name} {shading}: {against_cpu} against the CPU"
            );
            assert_eq!(bricked.samples, whole.samples, "{name} {shading}");
        }
        if gpu.filters() {
            // The texture unit filters within a brick: the apron holds the
            // cell's far corners.
            let settings = RenderSettings {
                sampling: Sampling::Filtered,
                ..Default::default()
            };
            gpu.brick_every_volume(None);
            let whole = gpu.render(scene, &rays, &settings, &desc).unwrap();
            gpu.brick_every_volume(Some(8));
            let bricked = gpu.render(scene, &rays, &settings, &desc).unwrap();
            let s = ssim(&bricked, &whole).unwrap();
            println!("{name} filtered: SSIM {s:.6} to one texture");
            assert!(s >= 0.9999, "{name} filtered: {s} against one texture");
        }
    }
}

#[test]
fn sixteen_bit_volumes_take_two_bytes_a_voxel_where_the_adapter_allows() {
    let mut gpu = gpu();
    let volume = as_uint16(&shepp_logan(20));
    let scene = Scene::shared(
        Arc::new(volume.into()),
        Arc::new(preset("phantom").unwrap()),
    );
    gpu.upload(&scene).unwrap();
    let per_voxel = gpu.volume_bytes() as f64 / 8000.0;
    println!("{}: {per_voxel} bytes a voxel", gpu.adapter().name);
    let expected = if gpu.has_16bit_textures() { 2.0 } else { 4.0 };
    assert_eq!(per_voxel, expected);
}

#[test]
fn a_gpu_budget_too_small_for_one_brick_is_refused_before_upload_and_auto_renders_on_the_cpu() {
    use anari_library_caveray::render::{Backend, RenderError, Renderer};
    let volume = Arc::new(shepp_logan(20).into());
    let scene = Scene::shared(Arc::clone(&volume), Arc::new(preset("phantom").unwrap()));
    // The same grid twice takes one texture: 8000 float32 voxels.
    let one = scene.volumes()[0].clone();
    let twice = Scene::placed(vec![one.clone(), one]).unwrap();
    let mut gpu = gpu();
    gpu.set_memory_budget(Some(32_000));
    gpu.upload(&twice).unwrap();
    // Past the budget the volume would be paged, but its pool would not
    // hold its one brick (20^3 voxels fit one).
    gpu.set_memory_budget(Some(31_999));
    let before = gpu.uploads().volumes;
    let err = gpu.upload(&scene).unwrap_err();
    assert!(
        matches!(err, RenderError::OutOfMemory { bytes: 32_000, .. }),
        "{err}"
    );
    assert!(
        err.to_string()
            .contains("past its share of the GPU memory budget of 31999 bytes"),
        "{err}"
    );
    assert_eq!(gpu.uploads().volumes, before, "nothing was uploaded");
    let mut asked_for_gpu = Renderer::Gpu(Box::new(gpu));
    let err = asked_for_gpu.upload_for(Backend::Gpu, &scene).unwrap_err();
    assert!(err.is_size(), "{err}");
    assert_eq!(asked_for_gpu.backend(), Backend::Gpu);
    let Renderer::Gpu(mut gpu) = asked_for_gpu else {
        unreachable!()
    };
    gpu.set_memory_budget(Some(31_999));
    let mut auto = Renderer::Gpu(gpu);
    let why = auto.upload_for(Backend::Auto, &scene).unwrap().unwrap();
    assert!(
        why.to_string().ends_with(
            "past its share of the GPU memory budget of 31999 bytes; rendering on the CPU"
        ),
        "{why}"
    );
    assert_eq!(auto.backend(), Backend::Cpu);
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(16, 16);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let frame = auto
        .render(
            &scene,
            &rays,
            &RenderSettings::default(),
            &FrameDesc::new(size),
        )
        .unwrap();
    assert!(frame.samples > 0);
}

#[test]
fn isosurfaces_the_gpu_cannot_hold_are_cast_on_the_cpu_under_auto() {
    use anari_library_caveray::render::iso::{IsoSettings, IsoSurface};
    use anari_library_caveray::render::{Backend, RenderError, Renderer};
    let surfaces = [IsoSurface {
        placed: common::iso::two_balls(24, glam::Mat4::IDENTITY),
        settings: IsoSettings::new(0.5),
    }];
    // 24^3 float32 voxels: 55296 bytes of texture.
    let mut asked = Renderer::Gpu(Box::new(gpu()));
    asked.set_gpu_budget(Some(55_296));
    assert!(asked.fit_surfaces(Backend::Auto, &surfaces).is_none());
    assert_eq!(asked.backend(), Backend::Gpu);
    asked.set_gpu_budget(Some(55_295));
    let Renderer::Gpu(g) = &asked else {
        unreachable!()
    };
    let err = g.check_iso(&surfaces[0].placed).unwrap_err();
    assert!(
        matches!(err, RenderError::OutOfMemory { bytes: 55_296, .. }),
        "{err}"
    );
    // Asked for the GPU, it stays there (and its cast says why it fails).
    assert!(asked.fit_surfaces(Backend::Gpu, &surfaces).is_none());
    assert_eq!(asked.backend(), Backend::Gpu);
    let why = asked.fit_surfaces(Backend::Auto, &surfaces).unwrap();
    assert!(why.to_string().ends_with("rendering on the CPU"), "{why}");
    assert_eq!(asked.backend(), Backend::Cpu);
}
