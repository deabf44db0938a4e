//! Scenes, cameras and renderers shared by the rendering tests.

use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::geometry::{
    pinhole_from_matrices, MatrixCamera, OffAxisCamera, OffAxisProjection, PinholeCamera,
    PrimaryRays, RayGen, Screen,
};
use anari_library_caveray::render::{CpuRenderer, GpuRenderer, Renderer};
use anari_library_caveray::scene::Scene;
use glam::{DVec3, UVec2};

/// The GPU renderer on Vulkan; tests never fall back to another API.
pub fn gpu() -> GpuRenderer {
    let gpu = GpuRenderer::new().unwrap_or_else(|e| {
        panic!("{e}: install mesa-vulkan-drivers and run through scripts/test")
    });
    assert_eq!(
        gpu.adapter().backend,
        wgpu::Backend::Vulkan,
        "adapter {} is not Vulkan",
        gpu.adapter().name
    );
    gpu
}

/// Both renderers, by name, to run the same checks on each.
pub fn renderers() -> Vec<(&'static str, Renderer)> {
    vec![
        ("gpu", Renderer::Gpu(Box::new(gpu()))),
        ("cpu", Renderer::Cpu(CpuRenderer::new())),
    ]
}

/// The Shepp-Logan phantom at `n`^3 on [-1, 1]^3 with its preset.
pub fn phantom(n: u32) -> Scene {
    let volume = shepp_logan(n);
    let tf = preset("phantom").unwrap();
    Scene::new(volume, tf)
}

/// A 2.4 x 2.4 wall at z = 2 in front of the [-1, 1]^3 volume, seen from
/// an eye off its centre normal, so every camera is genuinely off-axis.
pub fn off_axis_wall() -> (Screen, DVec3) {
    let screen = Screen::new(
        DVec3::new(-1.2, -1.2, 2.0),
        DVec3::new(1.2, -1.2, 2.0),
        DVec3::new(1.2, 1.2, 2.0),
    )
    .unwrap();
    (screen, DVec3::new(0.45, -0.3, 4.5))
}

/// The four cameras of one wall and eye, by name, lowered to ray generators.
pub fn four_cameras(screen: &Screen, eye: DVec3, size: UVec2) -> Vec<(&'static str, RayGen)> {
    let near = 0.01 * (eye - screen.centre()).length();
    let projection = OffAxisProjection::new(screen, eye, near, 1000.0 * near).unwrap();
    let matrix =
        MatrixCamera::from_f32(projection.view.as_mat4(), projection.proj.as_mat4()).unwrap();
    let recovered = pinhole_from_matrices(projection.view, projection.proj).unwrap();
    vec![
        (
            "offaxis",
            OffAxisCamera::new(*screen, eye).unwrap().ray_gen(size),
        ),
        ("matrix", matrix.ray_gen(size)),
        (
            "pinhole",
            PinholeCamera::from_screen(screen, eye)
                .unwrap()
                .ray_gen(size),
        ),
        ("from-matrices", recovered.camera.ray_gen(size)),
    ]
}

/// A camera on the +z axis looking at the origin through a square wall,
/// so the centre pixel of an odd-sized image passes through (0, 0).
pub fn axis_camera(distance: f64, half: f64) -> (Screen, DVec3) {
    let z = 1.5;
    let screen = Screen::new(
        DVec3::new(-half, -half, z),
        DVec3::new(half, -half, z),
        DVec3::new(half, half, z),
    )
    .unwrap();
    (screen, DVec3::new(0.0, 0.0, distance))
}

/// Balls of `material` at `centres` (radius `r`).
pub fn balls(
    centres: Vec<glam::Vec3>,
    r: f32,
    material: anari_library_caveray::scene::SurfaceMaterial,
) -> anari_library_caveray::scene::PlacedShape {
    use anari_library_caveray::scene::{PlacedShape, Shape, ShapeInput};
    let n = centres.len();
    let made = Shape::spheres(
        centres,
        vec![r; n],
        (0..n as u32).collect(),
        ShapeInput {
            vertices: n,
            primitives: n,
            attributes: Default::default(),
            ids: None,
        },
    )
    .unwrap();
    PlacedShape::new(
        std::sync::Arc::new(made.shape),
        material,
        glam::Mat4::IDENTITY,
    )
}
