//! Triangles, spheres, cones and curves beside a volume on the GPU, held to
//! the CPU reference: one march that stops at the nearest surface, its
//! color by attribute or constant, lit by a directional light or from the
//! eye, under any affine transform, and the BVH uploaded once.

use crate::common;

use std::sync::Arc;

use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::geometry::{ImageRegion, OrthographicCamera, PrimaryRays};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, ColorFormat, CpuRenderer, FrameDesc, Lamp, RenderSettings, Spot, SurfaceShading,
};
use anari_library_caveray::scene::{
    AlphaMode, Attribute, ColorSource, Image, Kept, OpacitySource, Pbr, PlacedShape, Sampler,
    SamplerKind, Scene, Shape, ShapeInput, SurfaceMaterial, Wrap,
};
use common::render::{four_cameras, gpu, off_axis_wall};
use glam::{DVec3, Mat4, UVec2, UVec3, Vec3, Vec4};

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
        opacity: OpacitySource::Constant(1.0),
        alpha: AlphaMode::Opaque,
        pbr: None,
    }
}

/// A bent sheet of 2 n^2 triangles through the volume behind its
/// centre, its vertex colors a gradient and its normals the host's.
fn sheet(n: u32) -> PlacedShape {
    sheet_colored(
        n,
        0,
        |u, v| Vec4::new(u, 0.3 + 0.5 * v, 1.0 - u, 1.0),
        ColorSource::Attribute(0),
    )
}

/// The sheet with `attribute(u, v)` per vertex in attribute slot `slot`,
/// in `color`.
fn sheet_colored(
    n: u32,
    slot: usize,
    attribute: impl Fn(f32, f32) -> Vec4,
    color: ColorSource,
) -> PlacedShape {
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
            colors.push(attribute(u, v));
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
        Kept::All(count),
        Some(normals.into()),
        input(vertices, count, slot, Some(Attribute::per_vertex(colors))),
    )
    .unwrap();
    PlacedShape::new(Arc::new(made.shape), material(color), Mat4::IDENTITY)
}

/// Spheres of several radii, sheared into ellipsoids, of a glossy
/// physically based material that glows a little.
fn glyphs() -> PlacedShape {
    glyphs_in(ColorSource::Constant(Vec3::new(0.9, 0.8, 0.2)))
}

fn glyphs_in(color: ColorSource) -> PlacedShape {
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
    let mut glossy = material(color);
    glossy.pbr = Some(Pbr {
        metallic: 0.6,
        roughness: 0.3,
        emissive: Vec3::new(0.05, 0.02, 0.0),
    });
    PlacedShape::new(Arc::new(made.shape), glossy, shear)
}

/// Three tubes: a cylinder capped at its first end, a cone tapering to a
/// point and one capped at both ends, colored per primitive through
/// attribute1.
fn tubes() -> PlacedShape {
    tubes_in(ColorSource::Attribute(2))
}

fn tubes_in(color: ColorSource) -> PlacedShape {
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
    let made = Shape::cones(
        "cone",
        positions,
        vec![[0, 1], [2, 3], [4, 5]],
        vec![[0.12, 0.12], [0.18, 0.0], [0.15, 0.06]],
        vec![[true, false], [true, true], [true, true]],
        input(6, 3, 2, Some(Attribute::per_primitive(colors))),
    )
    .unwrap();
    PlacedShape::new(
        Arc::new(made.shape),
        material(color),
        Mat4::from_rotation_y(0.3),
    )
}

/// A streamline: a helix of round curve segments whose radius swells and
/// shrinks, colored along it per vertex.
fn streamline() -> PlacedShape {
    let n = 14;
    let (mut positions, mut radii, mut colors) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        let u = i as f32 / (n - 1) as f32;
        let a = u * 9.0;
        positions.push(Vec3::new(
            0.7 * a.cos(),
            -1.0 + 2.0 * u,
            0.5 + 0.4 * a.sin(),
        ));
        radii.push(0.04 + 0.08 * (u * std::f32::consts::PI).sin());
        colors.push(Vec4::new(u, 1.0 - u, 0.5, 1.0));
    }
    let made = Shape::curves(
        positions,
        radii,
        (0..n as u32 - 1).collect(),
        input(n, n - 1, 0, Some(Attribute::per_vertex(colors))),
    )
    .unwrap();
    PlacedShape::new(
        Arc::new(made.shape),
        material(ColorSource::Attribute(0)),
        Mat4::from_rotation_x(0.2),
    )
}

fn mixed() -> Scene {
    Scene::new(shepp_logan(24), preset("phantom").unwrap())
        .with_shapes(vec![sheet(12), glyphs(), tubes(), streamline()])
        .unwrap()
}

fn lights() -> [(&'static str, RenderSettings); 3] {
    [
        ("eye light", RenderSettings::default()),
        (
            "headlight",
            RenderSettings {
                surface_shading: SurfaceShading::Lights,
                ..Default::default()
            },
        ),
        (
            "directional, point and spot",
            RenderSettings {
                surface_shading: SurfaceShading::Lights,
                headlight: false,
                light: Vec3::new(-0.4, 0.8, 0.5).normalize(),
                light_color: Vec3::new(1.0, 0.9, 0.8) * 1.5,
                ambient: Vec3::splat(0.2),
                lamps: vec![
                    Lamp {
                        position: Vec3::new(1.5, 1.0, 2.0),
                        color: Vec3::new(2.0, 1.5, 1.0),
                        spot: None,
                    },
                    Lamp {
                        position: Vec3::new(-1.0, 2.0, 1.5),
                        color: Vec3::new(0.5, 1.0, 3.0),
                        spot: Some(Spot {
                            direction: Vec3::new(0.4, -0.9, -0.5).normalize(),
                            cos_outer: 0.6f32.cos(),
                            cos_inner: 0.4f32.cos(),
                        }),
                    },
                ],
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
    let scene = Scene::of_shapes(vec![sheet(6), glyphs(), tubes(), streamline()]).unwrap();
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

/// A color map of `n` texels from blue through green to red.
fn color_map(n: u32, linear: bool) -> Image {
    let texels = (0..n)
        .map(|i| {
            let t = i as f32 / (n - 1) as f32;
            Vec4::new(t, 1.0 - (2.0 * t - 1.0).abs(), 1.0 - t, 1.0)
        })
        .collect();
    Image::new(UVec3::new(n, 1, 1), texels, linear, [Wrap::ClampToEdge; 3]).unwrap()
}

fn sampler(kind: SamplerKind) -> ColorSource {
    ColorSource::Sampler(Arc::new(Sampler::new(kind)))
}

#[test]
fn every_sampler_on_the_gpu_matches_the_cpu_reference() {
    // A scalar through a color map, as VTK colors by scalars, the range
    // stretched so that both ends clamp; a repeating checkerboard on
    // (u, v); per-primitive values; channels swapped by a transform.
    let mut scalars = Sampler::new(SamplerKind::Image(color_map(7, true)));
    scalars.in_transform = Mat4::from_scale(Vec3::splat(1.4));
    scalars.in_offset = Vec4::new(-0.2, 0.0, 0.0, 0.0);
    let checker: Vec<Vec4> = (0..16)
        .map(|i| {
            if (i % 4 + i / 4) % 2 == 0 {
                Vec4::ONE
            } else {
                Vec4::new(0.8, 0.2, 0.1, 1.0)
            }
        })
        .collect();
    let mut checkers = Sampler::new(SamplerKind::Image(
        Image::new(
            UVec3::new(4, 4, 1),
            checker,
            false,
            [Wrap::Repeat, Wrap::MirrorRepeat, Wrap::Repeat],
        )
        .unwrap(),
    ));
    checkers.in_transform = Mat4::from_scale(Vec3::splat(3.0));
    checkers.out_transform = Mat4::from_scale(Vec3::splat(0.9));
    checkers.out_offset = Vec4::new(0.05, 0.05, 0.05, 0.0);
    let per_primitive = sampler(SamplerKind::Primitive {
        values: vec![
            Vec4::new(0.2, 0.9, 0.9, 1.0),
            Vec4::new(0.9, 0.2, 0.9, 1.0),
            Vec4::new(0.9, 0.9, 0.2, 1.0),
            Vec4::ONE,
        ],
        offset: 0,
    });
    let mut swap = Sampler::new(SamplerKind::Transform);
    swap.in_attribute = Some(2);
    swap.out_transform = Mat4::from_cols(Vec4::Z, Vec4::X, Vec4::Y, Vec4::W);
    let scalar_sheet = sheet_colored(
        10,
        1,
        |u, _| Vec4::new(u, 0.0, 0.0, 1.0),
        ColorSource::Sampler(Arc::new(scalars)),
    );
    let mut checker_sheet = sheet_colored(4, 2, |u, v| Vec4::new(u, v, 0.0, 1.0), {
        let mut c = checkers;
        c.in_attribute = Some(2);
        ColorSource::Sampler(Arc::new(c))
    });
    checker_sheet.transform =
        Mat4::from_translation(Vec3::new(0.3, 0.2, 0.9)) * Mat4::from_scale(Vec3::splat(0.4));
    let scene = Scene::new(shepp_logan(16), preset("phantom").unwrap())
        .with_shapes(vec![
            scalar_sheet,
            checker_sheet,
            glyphs_in(per_primitive),
            tubes_in(ColorSource::Sampler(Arc::new(swap))),
        ])
        .unwrap();
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(48, 48);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
    let settings = RenderSettings::default();
    let g = gpu().render(&scene, &rays, &settings, &desc).unwrap();
    let c = CpuRenderer::new()
        .render(&scene, &rays, &settings, &desc)
        .unwrap();
    let s = ssim(&g, &c).unwrap();
    assert!(s >= 0.99, "GPU vs CPU SSIM {s}");
}

#[test]
fn a_color_map_colors_a_ramp_texel_by_texel() {
    // A square facing the camera, attribute0 = x across it, seen head-on
    // under the headlight without ambient light: each pixel shows the
    // texel its x falls in (nearest), or the blend of the two nearest
    // centres (linear).
    let square = |color: ColorSource| {
        let positions = vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        let u = vec![
            Vec4::new(0.0, 0.0, 0.0, 1.0),
            Vec4::new(1.0, 0.0, 0.0, 1.0),
            Vec4::new(1.0, 0.0, 0.0, 1.0),
            Vec4::new(0.0, 0.0, 0.0, 1.0),
        ];
        let made = Shape::triangles(
            positions,
            vec![[0, 1, 2], [0, 2, 3]],
            Kept::Listed(vec![0, 0]),
            None,
            input(4, 1, 1, Some(Attribute::per_vertex(u))),
        )
        .unwrap();
        Scene::of_shapes(vec![PlacedShape::new(
            Arc::new(made.shape),
            material(color),
            Mat4::IDENTITY,
        )])
        .unwrap()
    };
    let n = 32;
    let camera = head_on(n, 2.0);
    let settings = RenderSettings {
        ambient: Vec3::ZERO,
        ..Default::default()
    };
    let mut gpu = gpu();
    for linear in [false, true] {
        let map = color_map(4, linear);
        let scene = square(sampler(SamplerKind::Image(map.clone())));
        for (name, rgba) in both(&mut gpu, &scene, (&camera, n), &settings) {
            for x in 0..n {
                let u = (x as f32 + 0.5) / n as f32;
                let expected = map.at(Vec4::new(u, 0.0, 0.0, 1.0));
                let i = 4 * (n / 2 * n + x) as usize;
                let got = Vec3::from_slice(&rgba[i..i + 3]);
                assert!(
                    (got - expected.truncate()).abs().max_element() < 2e-3,
                    "{name} linear {linear} x {x}: {got} vs {expected}"
                );
            }
        }
    }
}

fn square_at(z: f32, color: Vec3, opacity: f32, alpha: AlphaMode) -> PlacedShape {
    let positions = vec![
        Vec3::new(-1.0, -1.0, z),
        Vec3::new(1.0, -1.0, z),
        Vec3::new(1.0, 1.0, z),
        Vec3::new(-1.0, 1.0, z),
    ];
    let made = Shape::triangles(
        positions,
        vec![[0, 1, 2], [0, 2, 3]],
        Kept::Listed(vec![0, 0]),
        None,
        input(4, 1, 0, None),
    )
    .unwrap();
    PlacedShape::new(
        Arc::new(made.shape),
        SurfaceMaterial {
            color: ColorSource::Constant(color),
            opacity: OpacitySource::Constant(opacity),
            alpha,
            pbr: None,
        },
        Mat4::IDENTITY,
    )
}

#[test]
fn translucent_and_masked_surfaces_composite_in_depth_order() {
    // Head-on under the headlight without ambient light, every surface
    // shows its own color: a half-opaque red square in front of a blue
    // one is half of each; masked below its cutoff the red one is not
    // there, above it it is opaque; in front of nothing it is half red
    // over the background.
    let n = 16;
    let camera = head_on(n, 4.0);
    let settings = RenderSettings {
        ambient: Vec3::ZERO,
        background: Vec4::new(0.0, 0.0, 0.0, 1.0),
        ..Default::default()
    };
    let desc = FrameDesc::new(UVec2::splat(n))
        .with_color(ColorFormat::Rgba32F)
        .with_depth();
    let blue = square_at(-0.5, Vec3::Z, 1.0, AlphaMode::Opaque);
    let cases = [
        (AlphaMode::Blend, 0.5, Vec3::new(0.5, 0.0, 0.5)),
        (AlphaMode::Mask(0.5), 0.4, Vec3::Z),
        (AlphaMode::Mask(0.3), 0.4, Vec3::X),
        (AlphaMode::Opaque, 0.4, Vec3::X),
        (AlphaMode::Blend, 0.0, Vec3::Z),
    ];
    let mut gpu = gpu();
    for (alpha, opacity, expected) in cases {
        let red = square_at(0.5, Vec3::X, opacity, alpha);
        let scene = Scene::of_shapes(vec![red, blue.clone()]).unwrap();
        for (name, rgba) in both(&mut gpu, &scene, (&camera, n), &settings) {
            let i = 4 * (n / 2 * n + n / 2) as usize;
            let got = Vec3::from_slice(&rgba[i..i + 3]);
            assert!(
                (got - expected).abs().max_element() < 1e-3,
                "{name} {alpha:?} {opacity}: {got}, expected {expected}"
            );
        }
    }
    // Half red over the black background alone; its depth is the red
    // square's, reached at the default threshold of a half.
    let red = square_at(0.5, Vec3::X, 0.5, AlphaMode::Blend);
    let scene = Scene::of_shapes(vec![red]).unwrap();
    let frame = CpuRenderer::new()
        .render(&scene, &camera, &settings, &desc)
        .unwrap();
    let anari_library_caveray::render::ColorData::Rgba32F(rgba) = &frame.color else {
        panic!("asked for RGBA32F");
    };
    let i = (n / 2 * n + n / 2) as usize;
    assert!((Vec3::from_slice(&rgba[4 * i..4 * i + 3]) - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-3);
    assert!((frame.depth.as_ref().unwrap()[i] - 2.5).abs() < 1e-4);
}

/// A red square at z = 0.5 over [-1, 1]^2 in `material` (its color
/// replaced where it is constant), attribute0 its vertex colors (red,
/// alpha from 0 at the left to 1 at the right) and attribute1 its x
/// mapped to [0, 1].
fn ramped_square(material: SurfaceMaterial) -> PlacedShape {
    let positions = vec![
        Vec3::new(-1.0, -1.0, 0.5),
        Vec3::new(1.0, -1.0, 0.5),
        Vec3::new(1.0, 1.0, 0.5),
        Vec3::new(-1.0, 1.0, 0.5),
    ];
    let u = [0.0, 1.0, 1.0, 0.0];
    let mut attributes: [Option<Attribute>; 5] = Default::default();
    attributes[0] = Some(Attribute::per_vertex(
        u.iter().map(|&u| Vec4::new(1.0, 0.0, 0.0, u)).collect(),
    ));
    attributes[2] = Some(Attribute::per_vertex(
        u.iter().map(|&u| Vec4::new(u, 0.0, 0.0, 1.0)).collect(),
    ));
    let made = Shape::triangles(
        positions,
        vec![[0, 1, 2], [0, 2, 3]],
        Kept::Listed(vec![0, 0]),
        None,
        ShapeInput {
            vertices: 4,
            primitives: 1,
            attributes,
            ids: None,
        },
    )
    .unwrap();
    PlacedShape::new(Arc::new(made.shape), material, Mat4::IDENTITY)
}

#[test]
fn opacity_from_an_attribute_a_sampler_or_the_colors_alpha_varies_across_a_surface() {
    // The ramped red square in front of an opaque blue one, head-on under
    // the headlight without ambient light: each pixel is red over blue
    // by the opacity its x gives, or red or blue alone where a mask cuts,
    // on both renderers.
    let n = 32;
    let camera = head_on(n, 2.0);
    let settings = RenderSettings {
        ambient: Vec3::ZERO,
        background: Vec4::new(0.0, 0.0, 0.0, 1.0),
        ..Default::default()
    };
    let blue = square_at(-0.5, Vec3::Z, 1.0, AlphaMode::Opaque);
    // Opacity steps of a nearest image: its first channel.
    let steps = Image::new(
        UVec3::new(4, 1, 1),
        [0.0, 0.25, 0.75, 1.0]
            .map(|a| Vec4::new(a, 0.0, 0.0, 1.0))
            .to_vec(),
        false,
        [Wrap::ClampToEdge; 3],
    )
    .unwrap();
    let step = |u: f32| [0.0, 0.25, 0.75, 1.0][((u * 4.0) as usize).min(3)];
    // Red whose fourth channel steps the same way.
    let red_steps = Image::new(
        UVec3::new(4, 1, 1),
        [0.0, 0.25, 0.75, 1.0]
            .map(|a| Vec4::new(1.0, 0.0, 0.0, a))
            .to_vec(),
        false,
        [Wrap::ClampToEdge; 3],
    )
    .unwrap();
    let by_x = |kind: SamplerKind| {
        let mut s = Sampler::new(kind);
        s.in_attribute = Some(2);
        Arc::new(s)
    };
    let mut half = Sampler::new(SamplerKind::Transform);
    half.in_attribute = Some(2);
    half.out_transform = Mat4::from_scale(Vec3::splat(0.5));
    let red = ColorSource::Constant(Vec3::X);
    let material = |color: ColorSource, opacity: OpacitySource, alpha: AlphaMode| SurfaceMaterial {
        color,
        opacity,
        alpha,
        pbr: None,
    };
    type Case = (&'static str, SurfaceMaterial, Box<dyn Fn(f32) -> f32>);
    let cases: Vec<Case> = vec![
        (
            "attribute, blend",
            material(red.clone(), OpacitySource::Attribute(2), AlphaMode::Blend),
            Box::new(|u| u),
        ),
        (
            "attribute, mask",
            material(
                red.clone(),
                OpacitySource::Attribute(2),
                AlphaMode::Mask(0.5),
            ),
            Box::new(|u| f32::from(u >= 0.5)),
        ),
        (
            "attribute, opaque",
            material(red.clone(), OpacitySource::Attribute(2), AlphaMode::Opaque),
            Box::new(|_| 1.0),
        ),
        (
            "image sampler, blend",
            material(
                red.clone(),
                OpacitySource::Sampler(by_x(SamplerKind::Image(steps.clone()))),
                AlphaMode::Blend,
            ),
            Box::new(step),
        ),
        (
            "image sampler, mask",
            material(
                red.clone(),
                OpacitySource::Sampler(by_x(SamplerKind::Image(steps))),
                AlphaMode::Mask(0.5),
            ),
            Box::new(move |u| f32::from(step(u) >= 0.5)),
        ),
        (
            "transform sampler, blend",
            material(
                red.clone(),
                OpacitySource::Sampler(Arc::new(half)),
                AlphaMode::Blend,
            ),
            Box::new(|u| 0.5 * u),
        ),
        (
            "color attribute's alpha times a constant, blend",
            material(
                ColorSource::Attribute(0),
                OpacitySource::Constant(0.8),
                AlphaMode::Blend,
            ),
            Box::new(|u| 0.8 * u),
        ),
        (
            "color image's alpha times an attribute, blend",
            material(
                ColorSource::Sampler(by_x(SamplerKind::Image(red_steps))),
                OpacitySource::Attribute(2),
                AlphaMode::Blend,
            ),
            Box::new(move |u| step(u) * u),
        ),
        (
            "color attribute's alpha, mask",
            material(
                ColorSource::Attribute(0),
                OpacitySource::Constant(1.0),
                AlphaMode::Mask(0.25),
            ),
            Box::new(|u| f32::from(u >= 0.25)),
        ),
    ];
    let mut gpu = gpu();
    for (what, drawn, opacity) in cases {
        let scene = Scene::of_shapes(vec![ramped_square(drawn), blue.clone()]).unwrap();
        for (name, rgba) in both(&mut gpu, &scene, (&camera, n), &settings) {
            for y in [1, n / 2, n - 2] {
                for x in 0..n {
                    let u = (x as f32 + 0.5) / n as f32;
                    let a = opacity(u);
                    let expected = Vec3::new(a, 0.0, 1.0 - a);
                    let i = 4 * (y * n + x) as usize;
                    let got = Vec3::from_slice(&rgba[i..i + 3]);
                    assert!(
                        (got - expected).abs().max_element() < 2e-3,
                        "{name}, {what}: pixel ({x}, {y}) {got}, expected {expected}"
                    );
                }
            }
        }
    }
}

#[test]
fn translucent_surfaces_inside_a_volume_on_the_gpu_match_the_cpu_reference() {
    let mut glass = glyphs();
    glass.material.opacity = OpacitySource::Constant(0.4);
    glass.material.alpha = AlphaMode::Blend;
    let mut veil = sheet(8);
    veil.material.opacity = OpacitySource::Constant(0.6);
    veil.material.alpha = AlphaMode::Blend;
    let scene = Scene::new(shepp_logan(16), preset("phantom").unwrap())
        .with_shapes(vec![veil, glass, tubes()])
        .unwrap();
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(40, 40);
    let rays = four_cameras(&screen, eye, size)[0].1;
    let desc = FrameDesc::new(size)
        .with_color(ColorFormat::Rgba32F)
        .with_depth();
    for (light, settings) in lights() {
        let g = gpu().render(&scene, &rays, &settings, &desc).unwrap();
        let c = CpuRenderer::new()
            .render(&scene, &rays, &settings, &desc)
            .unwrap();
        let s = ssim(&g, &c).unwrap();
        assert!(s >= 0.99, "{light}: GPU vs CPU SSIM {s}");
        let ratio = g.samples as f64 / c.samples as f64;
        assert!((ratio - 1.0).abs() < 0.02, "{light}: samples {ratio}");
    }
}

#[test]
fn point_and_spot_lights_fall_off_with_distance_and_cone() {
    // A white square at z = 0.5 seen head-on, lit only by a point light
    // 2 in front of its centre: the centre receives I / 4, a corner I
    // cos(a) / r^2. A narrow spot at the same place lights the centre
    // alone.
    let n = 17;
    let camera = head_on(n, 2.0);
    let scene = Scene::of_shapes(vec![square_at(0.5, Vec3::ONE, 1.0, AlphaMode::Opaque)]).unwrap();
    let point = Lamp {
        position: Vec3::new(0.0, 0.0, 2.5),
        color: Vec3::new(2.0, 1.0, 0.5),
        spot: None,
    };
    let spot = Lamp {
        spot: Some(Spot {
            direction: Vec3::NEG_Z,
            cos_outer: 0.3f32.cos(),
            cos_inner: 0.2f32.cos(),
        }),
        ..point
    };
    let mut gpu = gpu();
    for lamp in [point, spot] {
        let settings = RenderSettings {
            surface_shading: SurfaceShading::Lights,
            ambient: Vec3::ZERO,
            headlight: false,
            directional: false,
            lamps: vec![lamp],
            ..Default::default()
        };
        for (name, rgba) in both(&mut gpu, &scene, (&camera, n), &settings) {
            let at = |x: u32, y: u32| {
                let i = 4 * (y * n + x) as usize;
                Vec3::from_slice(&rgba[i..i + 3])
            };
            let centre = at(n / 2, n / 2);
            assert!(
                (centre - lamp.color / 4.0).abs().max_element() < 1e-3,
                "{name}: centre {centre}"
            );
            // The corner pixel's centre on the square, and what reaches it.
            let s = 2.0 / n as f32;
            let p = Vec3::new(-1.0 + 0.5 * s, -1.0 + 0.5 * s, 0.5);
            let offset = lamp.position - p;
            let cos = offset.normalize().z;
            let expected = match lamp.spot {
                None => lamp.color * cos / offset.length_squared(),
                Some(_) => Vec3::ZERO,
            };
            let corner = at(0, 0);
            assert!(
                (corner - expected).abs().max_element() < 1e-3,
                "{name}: corner {corner}, expected {expected}"
            );
        }
    }
}

/// A parallel view down -z from z = 3 of the square [-w/2, w/2]^2, n x n
/// pixels: pixel centres land on known points of a surface facing it.
fn head_on(n: u32, width: f64) -> anari_library_caveray::geometry::RayGen {
    OrthographicCamera::new(
        DVec3::new(0.0, 0.0, 3.0),
        DVec3::NEG_Z,
        DVec3::Y,
        width,
        1.0,
        ImageRegion::FULL,
    )
    .unwrap()
    .ray_gen(UVec2::splat(n))
}

/// `scene` through `camera` (n x n) on the CPU and on `gpu`, as RGBA32F
/// pixels.
fn both(
    gpu: &mut anari_library_caveray::render::GpuRenderer,
    scene: &Scene,
    (camera, n): (&anari_library_caveray::geometry::RayGen, u32),
    settings: &RenderSettings,
) -> [(&'static str, Vec<f32>); 2] {
    let desc = FrameDesc::new(UVec2::splat(n)).with_color(ColorFormat::Rgba32F);
    let rgba = |frame: anari_library_caveray::render::Frame| match frame.color {
        anari_library_caveray::render::ColorData::Rgba32F(c) => c,
        _ => panic!("asked for RGBA32F"),
    };
    [
        (
            "cpu",
            rgba(
                CpuRenderer::new()
                    .render(scene, camera, settings, &desc)
                    .unwrap(),
            ),
        ),
        (
            "gpu",
            rgba(gpu.render(scene, camera, settings, &desc).unwrap()),
        ),
    ]
}

/// A horizontal square over the left half of a cube of constant haze,
/// edge-on to a camera looking down -z: it shows nowhere, but stands
/// between the haze and a light straight above.
fn shaded_haze(square_opacity: Option<f32>) -> Scene {
    use anari_library_caveray::scene::{StructuredVolume, TransferFunction, Voxels};
    let n = 8u32;
    let volume = StructuredVolume::new(
        UVec3::splat(n),
        Voxels::F32(vec![0.5; (n * n * n) as usize].into()),
        Vec3::splat(-1.0),
        Vec3::splat(2.0 / (n - 1) as f32),
    )
    .unwrap();
    let tf = TransferFunction::new(vec![Vec4::ONE; 2], vec![0.6, 0.6], (0.0, 1.0), 1.0).unwrap();
    let scene = Scene::new(volume, tf);
    let Some(opacity) = square_opacity else {
        return scene;
    };
    let alpha = if opacity < 1.0 {
        AlphaMode::Blend
    } else {
        AlphaMode::Opaque
    };
    let mut square = square_at(0.0, Vec3::ONE, opacity, alpha);
    square.transform = Mat4::from_translation(Vec3::new(-1.0, 1.1, 0.0))
        * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2)
        * Mat4::from_scale(Vec3::new(1.0, 2.0, 1.0));
    scene.with_shapes(vec![square]).unwrap()
}

/// Mean red of the pixels left of x = -0.2 and right of x = 0.2 inside
/// the cube, n x n of a window 3 wide.
fn halves(frame: &anari_library_caveray::render::Frame, n: u32) -> (f32, f32) {
    let (mut left, mut right) = ((0.0, 0), (0.0, 0));
    for y in 0..n {
        for x in 0..n {
            let (px, py) = (
                -1.5 + 3.0 * (x as f32 + 0.5) / n as f32,
                -1.5 + 3.0 * (y as f32 + 0.5) / n as f32,
            );
            if py.abs() > 0.9 || px.abs() > 0.9 {
                continue;
            }
            let r = frame.pixel(x, y).x;
            if px < -0.2 {
                left = (left.0 + r, left.1 + 1);
            } else if px > 0.2 {
                right = (right.0 + r, right.1 + 1);
            }
        }
    }
    (left.0 / left.1 as f32, right.0 / right.1 as f32)
}

#[test]
fn shadow_and_ao_rays_of_the_volume_meet_the_surfaces() {
    use anari_library_caveray::render::Shading;
    let n = 24;
    let camera = head_on(n, 3.0);
    let desc = FrameDesc::new(UVec2::splat(n)).with_color(ColorFormat::Rgba32F);
    let settings = RenderSettings {
        shading: Shading::Shadows,
        light: Vec3::Y,
        ..Default::default()
    };
    let cpu = CpuRenderer::new();
    let render = |scene: &Scene| cpu.render(scene, &camera, &settings, &desc).unwrap();
    let (l, r) = halves(&render(&shaded_haze(None)), n);
    assert!((l - r).abs() < 0.01 * r, "no square: halves {l} and {r}");
    let (lo, ro) = halves(&render(&shaded_haze(Some(1.0))), n);
    assert!((ro - r).abs() < 1e-4, "the lit half changed: {ro} vs {r}");
    assert!(
        lo < 0.8 * ro,
        "under the opaque square: {lo}, beside it {ro}"
    );
    let (lt, rt) = halves(&render(&shaded_haze(Some(0.5))), n);
    assert!(
        lo < lt && lt < rt,
        "translucent: {lt} between {lo} and {rt}"
    );
    // The GPU's shadow and AO rays meet the same surfaces.
    let mut gpu = gpu();
    for shading in [Shading::Shadows, Shading::ShadowsAo] {
        let settings = RenderSettings {
            shading,
            ..settings.clone()
        };
        for opacity in [1.0, 0.5] {
            let scene = shaded_haze(Some(opacity));
            let g = gpu.render(&scene, &camera, &settings, &desc).unwrap();
            let c = cpu.render(&scene, &camera, &settings, &desc).unwrap();
            let s = ssim(&g, &c).unwrap();
            assert!(
                s >= 0.99,
                "{shading:?}, opacity {opacity}: GPU vs CPU SSIM {s}"
            );
            let ((gl, _), (cl, _)) = (halves(&g, n), halves(&c, n));
            assert!(
                (gl - cl).abs() < 0.01,
                "{shading:?}: GPU {gl}, CPU {cl} under the square"
            );
        }
    }
}
