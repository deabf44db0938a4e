//! Triangles, spheres and cylinders beside a volume on the GPU, held to
//! the CPU reference: one march that stops at the nearest surface, its
//! color by attribute or constant, lit by a directional light or from the
//! eye, under any affine transform, and the BVH uploaded once.

use crate::common;

use std::sync::Arc;

use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{ssim, ColorFormat, CpuRenderer, FrameDesc, RenderSettings};
use anari_library_caveray::scene::{
    Attribute, ColorSource, PlacedShape, Scene, Shape, ShapeInput, SurfaceMaterial,
};
use common::render::{four_cameras, gpu, off_axis_wall};
use glam::{Mat4, UVec2, Vec3, Vec4};

fn input(vertices: usize, primitives: usize, slot: usize, a: Option<Attribute>) -> ShapeInput {
    let mut attributes: [Option<Attribute>; 5] = Default::default();
    attributes[slot] = a;
    ShapeInput {
        vertices,
        primitives,
        attributes,
        ids: None,
    }
}

fn material(color: ColorSource) -> SurfaceMaterial {
    SurfaceMaterial {
        color,
        opacity: 1.0,
    }
}

/// A bent sheet of 2 n^2 triangles through the volume behind its
/// centre, its vertex colors a gradient and its normals the host's.
fn sheet(n: u32) -> PlacedShape {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut colors = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            let x = -1.3 + 2.6 * u;
            let y = -1.3 + 2.6 * v;
            let z = -0.4 + 0.3 * (2.0 * x).sin();
            positions.push(Vec3::new(x, y, z));
            normals.push(Vec3::new(-0.6 * (2.0 * x).cos(), 0.0, 1.0));
            colors.push(Vec4::new(u, 0.3 + 0.5 * v, 1.0 - u, 1.0));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
    }
    let count = triangles.len();
    let vertices = positions.len();
    let made = Shape::triangles(
        positions,
        triangles,
        (0..count as u32).collect(),
        Some(normals),
        input(vertices, count, 0, Some(Attribute::PerVertex(colors))),
    )
    .unwrap();
    PlacedShape::new(
        Arc::new(made.shape),
        material(ColorSource::Attribute(0)),
        Mat4::IDENTITY,
    )
}

/// Spheres of several radii, sheared into ellipsoids.
fn glyphs() -> PlacedShape {
    let positions = vec![
        Vec3::new(0.6, 0.5, 0.3),
        Vec3::new(-0.5, 0.6, -0.2),
        Vec3::new(0.0, 0.1, 0.9),
        Vec3::new(-0.7, -0.6, 0.6),
    ];
    let radii = vec![0.3, 0.2, 0.25, 0.35];
    let made = Shape::spheres(positions, radii, vec![0, 1, 2, 3], input(4, 4, 0, None)).unwrap();
    let shear = Mat4::from_cols(
        Vec4::new(1.0, 0.0, 0.0, 0.0),
        Vec4::new(0.4, 0.8, 0.0, 0.0),
        Vec4::new(0.0, 0.0, 1.2, 0.0),
        Vec4::new(0.1, 0.0, 0.0, 1.0),
    );
    PlacedShape::new(
        Arc::new(made.shape),
        material(ColorSource::Constant(Vec3::new(0.9, 0.8, 0.2))),
        shear,
    )
}

/// Three tubes, one cap each, colored per primitive through attribute1.
fn tubes() -> PlacedShape {
    let positions = vec![
        Vec3::new(-1.0, 0.9, 0.0),
        Vec3::new(1.0, 0.9, 0.4),
        Vec3::new(0.2, -1.0, 0.5),
        Vec3::new(0.3, 1.0, 0.7),
        Vec3::new(-0.8, -0.2, -0.9),
        Vec3::new(0.9, -0.1, 1.1),
    ];
    let colors = vec![
        Vec4::new(1.0, 0.2, 0.2, 1.0),
        Vec4::new(0.2, 1.0, 0.3, 1.0),
        Vec4::new(0.3, 0.4, 1.0, 1.0),
    ];
    let made = Shape::cylinders(
        positions,
        vec![[0, 1], [2, 3], [4, 5]],
        vec![0.12, 0.1, 0.15],
        [true, false],
        input(6, 3, 2, Some(Attribute::PerPrimitive(colors))),
    )
    .unwrap();
    PlacedShape::new(
        Arc::new(made.shape),
        material(ColorSource::Attribute(2)),
        Mat4::from_rotation_y(0.3),
    )
}

fn mixed() -> Scene {
    Scene::new(shepp_logan(24), preset("phantom").unwrap())
        .with_shapes(vec![sheet(12), glyphs(), tubes()])
        .unwrap()
}

fn lights() -> [(&'static str, RenderSettings); 2] {
    [
        ("headlight", RenderSettings::default()),
        (
            "directional",
            RenderSettings {
                headlight: false,
                light: Vec3::new(-0.4, 0.8, 0.5).normalize(),
                light_color: Vec3::new(1.0, 0.9, 0.8) * 1.5,
                ambient: Vec3::splat(0.2),
                ..Default::default()
            },
        ),
    ]
}

#[test]
fn surfaces_inside_a_volume_on_the_gpu_match_the_cpu_reference() {
    let scene = mixed();
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(40, 40);
    let mut gpu = gpu();
    let cpu = CpuRenderer::new();
    for (camera, rays) in four_cameras(&screen, eye, size).into_iter().take(2) {
        for (light, settings) in lights() {
            let desc = FrameDesc::new(size)
                .with_color(ColorFormat::Rgba32F)
                .with_depth();
            let g = gpu.render(&scene, &rays, &settings, &desc).unwrap();
            let c = cpu.render(&scene, &rays, &settings, &desc).unwrap();
            let s = ssim(&g, &c).unwrap();
            assert!(s >= 0.99, "{camera} {light}: GPU vs CPU SSIM {s}");
            // Depth: the nearer of surface and volume, alike but for the
            // odd silhouette pixel.
            let (gd, cd) = (g.depth.clone().unwrap(), c.depth.clone().unwrap());
            let off = gd
                .iter()
                .zip(&cd)
                .filter(|(a, b)| {
                    !(a.is_infinite() && b.is_infinite() || (*a - *b).abs() < 1e-3 * b.abs())
                })
                .count();
            assert!(
                off <= gd.len() / 100,
                "{camera} {light}: {off} depths differ"
            );
            let surfaced = cd.iter().filter(|d| d.is_finite()).count();
            assert!(
                surfaced > gd.len() / 4,
                "{camera}: the surfaces hardly show"
            );
        }
    }
    // One BVH for every render of the same shapes; a new shape list
    // builds and uploads another.
    assert_eq!(gpu.uploads().surfaces, 1);
    let fewer = Scene::new(shepp_logan(24), preset("phantom").unwrap())
        .with_shapes(vec![glyphs()])
        .unwrap();
    let rays = four_cameras(&screen, eye, size)[0].1;
    gpu.render(
        &fewer,
        &rays,
        &RenderSettings::default(),
        &FrameDesc::new(size),
    )
    .unwrap();
    assert_eq!(gpu.uploads().surfaces, 2);
}

#[test]
fn surfaces_without_a_volume_render_on_the_gpu_as_on_the_cpu() {
    let scene = Scene::of_shapes(vec![sheet(6), glyphs(), tubes()]).unwrap();
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(32, 32);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
    let settings = RenderSettings::default();
    let g = gpu().render(&scene, &rays, &settings, &desc).unwrap();
    let c = CpuRenderer::new()
        .render(&scene, &rays, &settings, &desc)
        .unwrap();
    let s = ssim(&g, &c).unwrap();
    assert!(s >= 0.99, "GPU vs CPU SSIM {s}");
    assert_eq!(g.samples, 0);
}
