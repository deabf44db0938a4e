//! What each pixel's depth shows (the frame's primitiveId, objectId,
//! instanceId, normal and albedo channels): a sphere's normals and ids
//! against their analytic values, a volume's, the host's primitive ids,
//! and the GPU held to the CPU on an off-axis wall of surfaces in a
//! volume.

use crate::common;

use std::sync::Arc;

use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::geometry::{ImageRegion, OrthographicCamera, PrimaryRays, RayGen};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{CpuRenderer, Frame, FrameDesc, PixelHit, RenderSettings};
use anari_library_caveray::scene::{
    AlphaMode, ColorSource, Kept, ObjectIds, OpacitySource, PlacedShape, PlacedVolume, Scene,
    Shape, ShapeInput, SurfaceMaterial, TransferFunction,
};
use common::render::{four_cameras, gpu, off_axis_wall};
use glam::{DVec3, Mat4, UVec2, Vec3, Vec4};

const N: u32 = 32;

/// Looking down -z from z = 3 at the square [-1.5, 1.5]^2, N x N.
fn head_on() -> RayGen {
    OrthographicCamera::new(
        DVec3::new(0.0, 0.0, 3.0),
        DVec3::NEG_Z,
        DVec3::Y,
        3.0,
        1.0,
        ImageRegion::FULL,
    )
    .unwrap()
    .ray_gen(UVec2::splat(N))
}

/// Pixel (x, y)'s centre in world x, y.
fn centre(x: u32, y: u32) -> (f32, f32) {
    let s = 3.0 / N as f32;
    (-1.5 + (x as f32 + 0.5) * s, -1.5 + (y as f32 + 0.5) * s)
}

fn input(vertices: usize, primitives: usize, ids: Option<Vec<u32>>) -> ShapeInput {
    ShapeInput {
        vertices,
        primitives,
        attributes: Default::default(),
        ids,
    }
}

fn matte(color: Vec3) -> SurfaceMaterial {
    SurfaceMaterial {
        color: ColorSource::Constant(color),
        opacity: OpacitySource::Constant(1.0),
        alpha: AlphaMode::Opaque,
        pbr: None,
    }
}

fn ids(object: u32, instance: u32) -> ObjectIds {
    ObjectIds { object, instance }
}

/// Three spheres of radius 1 at the origin, the host's primitives 0 and
/// 1 dropped (zero radius), the third reported by its `primitive.id` 42;
/// as surface 7 of instance 3, placed by `transform`.
fn sphere(transform: Mat4) -> PlacedShape {
    let made = Shape::spheres(
        vec![Vec3::X * 9.0, Vec3::Y * 9.0, Vec3::ZERO],
        vec![0.0, 0.0, 1.0],
        vec![0, 1, 2],
        input(3, 3, Some(vec![40, 41, 42])),
    )
    .unwrap();
    let mut placed = PlacedShape::new(
        Arc::new(made.shape),
        matte(Vec3::new(0.8, 0.4, 0.1)),
        transform,
    );
    placed.ids = ids(7, 3);
    placed
}

fn with_hits(n: UVec2) -> FrameDesc {
    FrameDesc::new(n).with_depth().with_hits()
}

/// `scene` head-on on the CPU, N x N, with depth and hits.
fn head_on_hits(scene: &Scene) -> Frame {
    CpuRenderer::new()
        .render(
            scene,
            &head_on(),
            &RenderSettings::default(),
            &with_hits(UVec2::splat(N)),
        )
        .unwrap()
}

fn hits(frame: &Frame) -> &[PixelHit] {
    frame.hits.as_deref().expect("the frame has hits")
}

#[test]
fn a_sphere_reports_its_ids_normals_and_albedo_and_the_background_nothing() {
    let scene = Scene::of_shapes(vec![sphere(Mat4::IDENTITY)]).unwrap();
    let frame = head_on_hits(&scene);
    let hits = hits(&frame);
    let (mut inside, mut outside) = (0, 0);
    for y in 0..N {
        for x in 0..N {
            let (px, py) = centre(x, y);
            let r2 = px * px + py * py;
            let h = hits[(y * N + x) as usize];
            // Pixels the silhouette cuts are left out.
            if r2 < 0.9 {
                inside += 1;
                assert_eq!(
                    (h.primitive, h.object, h.instance),
                    (42, 7, 3),
                    "({x}, {y})"
                );
                let n = Vec3::from(h.normal);
                let expected = Vec3::new(px, py, (1.0 - r2).sqrt());
                assert!(
                    n.dot(expected) > 0.999,
                    "({x}, {y}): normal {n}, not {expected}"
                );
                assert!(
                    (Vec3::from(h.albedo) - Vec3::new(0.8, 0.4, 0.1))
                        .abs()
                        .max_element()
                        < 1e-6
                );
            } else if r2 > 1.1 {
                outside += 1;
                assert_eq!(h, PixelHit::NOTHING, "({x}, {y})");
            }
        }
    }
    assert!(
        inside > 200 && outside > 200,
        "{inside} inside, {outside} outside"
    );
}

/// A slab of the phantom's values, id 5, placed directly (instance none).
fn volume() -> PlacedVolume {
    PlacedVolume {
        volume: Arc::new(shepp_logan(24).into()),
        transfer_function: Arc::new(preset("phantom").unwrap()),
        transform: Mat4::IDENTITY,
        ids: ids(5, u32::MAX),
    }
}

#[test]
fn a_volume_reports_its_id_its_colors_and_normals_facing_the_camera() {
    // An opaque white table: the albedo is the table's color, wherever
    // the depth is taken.
    let white = TransferFunction::new(vec![Vec4::ONE; 2], vec![1.0, 1.0], (0.0, 1.0), 1.0).unwrap();
    let placed = PlacedVolume {
        transfer_function: Arc::new(white),
        ..volume()
    };
    let scene = Scene::placed(vec![placed]).unwrap();
    let frame = head_on_hits(&scene);
    let depth = frame.depth.as_deref().unwrap();
    let mut seen = 0;
    for (i, h) in hits(&frame).iter().enumerate() {
        if depth[i].is_infinite() {
            assert_eq!(*h, PixelHit::NOTHING, "pixel {i}");
            continue;
        }
        seen += 1;
        assert_eq!(
            (h.primitive, h.object, h.instance),
            (0, 5, u32::MAX),
            "pixel {i}"
        );
        assert_eq!(h.albedo, [1.0; 3], "pixel {i}");
        let n = Vec3::from(h.normal);
        assert!((n.length() - 1.0).abs() < 1e-4, "pixel {i}: {n}");
        // Facing the camera, which looks down -z.
        assert!(n.z >= 0.0, "pixel {i}: {n}");
    }
    assert!(seen > (N * N / 4) as usize, "{seen} pixels show the volume");
}

/// The sphere at half size, its centre at (0.3, 0.2, 0).
fn small() -> Mat4 {
    Mat4::from_translation(Vec3::new(0.3, 0.2, 0.0)) * Mat4::from_scale(Vec3::splat(0.5))
}

#[test]
fn each_pixel_reports_the_sphere_or_the_volume_by_which_set_its_depth() {
    let scene = Scene::placed(vec![volume()])
        .unwrap()
        .with_shapes(vec![sphere(small())])
        .unwrap();
    let frame = head_on_hits(&scene);
    let depth = frame.depth.as_deref().unwrap();
    let mut seen = [0; 2];
    for (i, h) in hits(&frame).iter().enumerate() {
        let (x, y) = centre(i as u32 % N, i as u32 / N);
        let r2 = (x - 0.3).powi(2) + (y - 0.2).powi(2);
        // Orthographic from z = 3: the sphere's front is 3 - z away.
        let front = (r2 < 0.25).then(|| 3.0 - (0.25 - r2).sqrt());
        match front {
            Some(t) if (depth[i] - t).abs() < 1e-3 => {
                assert_eq!(h.object, 7, "pixel {i} at the sphere's depth");
                seen[0] += 1;
            }
            _ if depth[i].is_finite() => {
                assert_eq!(h.object, 5, "pixel {i} at the volume's depth");
                seen[1] += 1;
            }
            _ => assert_eq!(*h, PixelHit::NOTHING, "pixel {i}"),
        }
    }
    assert!(
        seen[0] > 50 && seen[1] > 20,
        "sphere and volume pixels: {seen:?}"
    );
}

#[test]
fn the_gpu_records_what_the_cpu_records_on_an_off_axis_wall() {
    let scene = Scene::placed(vec![volume()])
        .unwrap()
        .with_shapes(vec![sphere(small()), sheet()])
        .unwrap();
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(40, 40);
    let mut gpu = gpu();
    let cpu = CpuRenderer::new();
    let settings = RenderSettings::default();
    for (camera, rays) in four_cameras(&screen, eye, size).into_iter().take(2) {
        let desc = with_hits(size);
        let g = gpu.render(&scene, &rays, &settings, &desc).unwrap();
        let c = cpu.render(&scene, &rays, &settings, &desc).unwrap();
        let (gh, ch) = (hits(&g), hits(&c));
        let ids_differ = gh
            .iter()
            .zip(ch)
            .filter(|(a, b)| {
                (a.primitive, a.object, a.instance) != (b.primitive, b.object, b.instance)
            })
            .count();
        // Silhouette pixels may fall either way.
        assert!(
            ids_differ <= gh.len() / 50,
            "{camera}: {ids_differ} ids differ"
        );
        let shaded_differ = gh
            .iter()
            .zip(ch)
            .filter(|(a, b)| a.object == b.object && a.object != u32::MAX)
            .filter(|(a, b)| {
                Vec3::from(a.normal).dot(Vec3::from(b.normal)) < 0.99
                    || (Vec3::from(a.albedo) - Vec3::from(b.albedo))
                        .abs()
                        .max_element()
                        > 0.02
            })
            .count();
        assert!(
            shaded_differ <= gh.len() / 50,
            "{camera}: {shaded_differ} normals or albedos differ"
        );
        for object in [5, 7, 9] {
            assert!(
                ch.iter().any(|h| h.object == object),
                "{camera}: object {object} not seen"
            );
        }
    }
}

/// A square of two triangles, its host primitives 0 and 1, in front of
/// the volume, as surface 9 placed by instance 4.
fn sheet() -> PlacedShape {
    let positions = vec![
        Vec3::new(-0.9, -0.9, 0.95),
        Vec3::new(-0.2, -0.9, 0.95),
        Vec3::new(-0.2, -0.2, 0.95),
        Vec3::new(-0.9, -0.2, 0.95),
    ];
    let made = Shape::triangles(
        positions,
        vec![[0, 1, 2], [0, 2, 3]],
        Kept::All(2),
        None,
        input(4, 2, None),
    )
    .unwrap();
    let mut placed = PlacedShape::new(
        Arc::new(made.shape),
        matte(Vec3::new(0.2, 0.6, 0.9)),
        Mat4::IDENTITY,
    );
    placed.ids = ids(9, 4);
    placed
}
