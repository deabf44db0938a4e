use std::sync::Arc;

use glam::{DVec3, Mat4, UVec2, UVec3, Vec3, Vec4};

use super::*;
use crate::geometry::{ImageRegion, OrthographicCamera, PrimaryRays};
use crate::render::simd::Level;
use crate::render::{ColorFormat, CpuRenderer, Frame, FrameDesc, Render};
use crate::scene::{
    AlphaMode, Kept, Scene, Shape, ShapeInput, StructuredVolume, SurfaceMaterial, TransferFunction,
    Voxels,
};

const N: u32 = 32;

/// Looking down -z from z = 5 at the square [-2, 2]^2.
fn camera() -> RayGenOf {
    let c = OrthographicCamera::new(
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::NEG_Z,
        DVec3::Y,
        4.0,
        1.0,
        ImageRegion::FULL,
    )
    .unwrap();
    RayGenOf(c.ray_gen(UVec2::splat(N)))
}

struct RayGenOf(crate::geometry::RayGen);

/// Pixel (x, y)'s centre in world x, y.
fn centre(x: u32, y: u32) -> (f32, f32) {
    let s = 4.0 / N as f32;
    (-2.0 + (x as f32 + 0.5) * s, -2.0 + (y as f32 + 0.5) * s)
}

fn input(vertices: usize, primitives: usize) -> ShapeInput {
    ShapeInput {
        vertices,
        primitives,
        attributes: Default::default(),
        ids: None,
    }
}

fn unit_sphere(color: ColorSource, transform: Mat4) -> PlacedShape {
    let made = Shape::spheres(vec![Vec3::ZERO], vec![1.0], vec![0], input(1, 1)).unwrap();
    PlacedShape::new(
        Arc::new(made.shape),
        SurfaceMaterial {
            color,
            opacity: OpacitySource::Constant(1.0),
            alpha: AlphaMode::Opaque,
            pbr: None,
        },
        transform,
    )
}

fn render(scene: &Scene, settings: &RenderSettings) -> Frame {
    let desc = FrameDesc::new(UVec2::splat(N))
        .with_color(ColorFormat::Rgba32F)
        .with_depth();
    CpuRenderer::reference()
        .render(scene, &camera().0, settings, &desc)
        .unwrap()
}

/// Lambertian in a light at the eye (the world has none), without the
/// ambient light: a pixel's shade is its normal's z.
fn unlit_ambient() -> RenderSettings {
    RenderSettings {
        ambient: Vec3::ZERO,
        surface_shading: crate::render::SurfaceShading::Lights,
        ..RenderSettings::default()
    }
}

#[test]
fn a_sphere_shows_its_silhouette_depth_and_headlit_shading() {
    let red = ColorSource::Constant(Vec3::new(1.0, 0.0, 0.0));
    let scene = Scene::of_shapes(vec![unit_sphere(red, Mat4::IDENTITY)]).unwrap();
    // The reference device's eye light blends the cosine with the color.
    let blend = 0.3;
    let eye = RenderSettings {
        surface_shading: crate::render::SurfaceShading::EyeLight { blend },
        ..RenderSettings::default()
    };
    for (settings, shade) in [
        (unlit_ambient(), &(|z: f32| z) as &dyn Fn(f32) -> f32),
        (eye, &|z: f32| blend * z + 1.0 - blend),
    ] {
        sphere_check(&scene, &settings, shade);
    }
}

fn sphere_check(scene: &Scene, settings: &RenderSettings, shade: &dyn Fn(f32) -> f32) {
    let frame = render(scene, settings);
    let depth = frame.depth.clone().unwrap();
    let half_pixel = 2.0 / N as f32;
    for y in 0..N {
        for x in 0..N {
            let (px, py) = centre(x, y);
            let r = (px * px + py * py).sqrt();
            let (c, d) = (frame.pixel(x, y), depth[(y * N + x) as usize]);
            if r < 1.0 - half_pixel {
                let z = (1.0 - r * r).sqrt();
                assert!((d - (5.0 - z)).abs() < 1e-4, "depth at {x},{y}: {d}");
                // Lit from the eye: the cosine is the normal's z.
                assert!(
                    (c.x - shade(z)).abs() < 1e-4 && c.y == 0.0,
                    "color at {x},{y}: {c}"
                );
            } else if r > 1.0 + half_pixel {
                assert_eq!(d, f32::INFINITY);
                assert_eq!(c, RenderSettings::default().background);
            }
        }
    }
}

#[test]
fn an_instance_stretches_a_sphere_into_an_ellipsoid() {
    let white = ColorSource::Constant(Vec3::ONE);
    let stretch = Mat4::from_scale(Vec3::new(1.8, 0.5, 1.0));
    let scene = Scene::of_shapes(vec![unit_sphere(white, stretch)]).unwrap();
    let frame = render(&scene, &unlit_ambient());
    let depth = frame.depth.unwrap();
    for y in 0..N {
        for x in 0..N {
            let (px, py) = centre(x, y);
            let e = (px / 1.8).powi(2) + (py / 0.5).powi(2);
            let d = depth[(y * N + x) as usize];
            if e < 0.8 {
                assert!((d - (5.0 - (1.0 - e).sqrt())).abs() < 1e-4, "{x},{y}: {d}");
            } else if e > 1.25 {
                assert_eq!(d, f32::INFINITY, "{x},{y}");
            }
        }
    }
}

/// A triangle over most of the image, red, green and blue at its corners.
fn rgb_triangle(z: f32) -> PlacedShape {
    let p = vec![
        Vec3::new(-1.9, -1.9, z),
        Vec3::new(1.9, -1.9, z),
        Vec3::new(-1.9, 1.9, z),
    ];
    let mut inp = input(3, 1);
    inp.attributes[0] = Some(Attribute::per_vertex(vec![Vec4::X, Vec4::Y, Vec4::Z]));
    let made = Shape::triangles(p, vec![[0, 1, 2]], Kept::All(1), None, inp).unwrap();
    PlacedShape::new(
        Arc::new(made.shape),
        SurfaceMaterial {
            color: ColorSource::Attribute(0),
            opacity: OpacitySource::Constant(1.0),
            alpha: AlphaMode::Opaque,
            pbr: None,
        },
        Mat4::IDENTITY,
    )
}

#[test]
fn a_triangle_interpolates_its_vertex_colors_barycentrically() {
    let scene = Scene::of_shapes(vec![rgb_triangle(0.0)]).unwrap();
    let frame = render(&scene, &unlit_ambient());
    let mut inside = 0;
    for y in 0..N {
        for x in 0..N {
            let (px, py) = centre(x, y);
            let (u, v) = ((px + 1.9) / 3.8, (py + 1.9) / 3.8);
            if u < 0.01 || v < 0.01 || u + v > 0.98 {
                continue;
            }
            inside += 1;
            let want = Vec3::new(1.0 - u - v, u, v);
            let got = frame.pixel(x, y).truncate();
            assert!(
                (got - want).abs().max_element() < 1e-4,
                "{x},{y}: {got} vs {want}"
            );
        }
    }
    assert!(inside > 400);
}

/// A slab of constant density filling z in [-1, 1] over the image.
fn slab() -> Scene {
    let volume = StructuredVolume::new(
        UVec3::new(4, 4, 4),
        Voxels::F32(vec![1.0; 64].into()),
        Vec3::new(-2.0, -2.0, -1.0),
        Vec3::new(4.0 / 3.0, 4.0 / 3.0, 2.0 / 3.0),
    )
    .unwrap();
    let tf = TransferFunction::new(
        vec![Vec4::new(0.2, 0.4, 1.0, 1.0)],
        vec![0.3],
        (0.0, 1.0),
        1.0,
    )
    .unwrap();
    Scene::new(volume, tf)
}

#[test]
fn a_surface_in_a_volume_ends_the_march_and_the_nearer_depth_is_reported() {
    let settings = unlit_ambient();
    let alone = render(&slab(), &settings);
    // In front of the volume the surface hides it.
    let front = slab().with_shapes(vec![rgb_triangle(1.5)]).unwrap();
    let surface_only = render(
        &Scene::of_shapes(vec![rgb_triangle(1.5)]).unwrap(),
        &settings,
    );
    let f = render(&front, &settings);
    // Inside, the volume in front of the surface is composited over it:
    // the same as the volume cut at the surface by a clip plane, over a
    // background of the surface's color.
    let inside = slab().with_shapes(vec![rgb_triangle(0.0)]).unwrap();
    let i = render(&inside, &settings);
    let mut clipped = settings.clone();
    clipped.clip_planes =
        crate::render::ClipPlanes::new(&[Vec4::new(0.0, 0.0, -1.0, 0.0)]).unwrap();
    let (x, y) = (8, 8);
    let behind = render(
        &Scene::of_shapes(vec![rgb_triangle(0.0)]).unwrap(),
        &settings,
    )
    .pixel(x, y);
    clipped.background = behind;
    let want = render(&slab(), &clipped).pixel(x, y);
    let fd = f.depth.as_ref().unwrap();
    let at = (y * N + x) as usize;
    assert_eq!(f.pixel(x, y), surface_only.pixel(x, y));
    assert!((fd[at] - 3.5).abs() < 1e-4);
    assert!(
        (i.pixel(x, y) - want).abs().max_element() < 1e-5,
        "{} vs {want}",
        i.pixel(x, y)
    );
    // The nearer of the surface and the volume's depth is the frame's:
    // the volume turns half opaque past z = 0 here, before z = -0.95.
    let volume_depth = alone.depth.as_ref().unwrap()[at];
    assert!(volume_depth > 5.0 && volume_depth < 5.95, "{volume_depth}");
    assert!((i.depth.as_ref().unwrap()[at] - 5.0).abs() < 1e-4);
    let back = slab().with_shapes(vec![rgb_triangle(-0.95)]).unwrap();
    // Within the last, shortened step before the surface.
    let d = render(&back, &settings).depth.unwrap()[at];
    assert!(
        (d - volume_depth).abs() < 0.1 && d < 5.95,
        "{d} vs {volume_depth}"
    );
    // Outside the triangle the volume shows as it does alone.
    assert_eq!(i.pixel(N - 1, N - 1), alone.pixel(N - 1, N - 1));
}

/// Numbers in [0, 1] from `seed`, the same on every run (xorshift).
fn random(mut seed: u32) -> impl FnMut() -> f32 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed as f32 / u32::MAX as f32
    }
}

/// A cloud of `triangles` small triangles (some of them sharing edges)
/// and 100 spheres, turned by an instance, the same spheres unturned,
/// and a source of random numbers in [0, 1].
fn cloud(triangles: u32) -> ([PlacedShape; 3], impl FnMut() -> f32) {
    let mut rnd = random(7);
    let mut p = Vec::new();
    let mut tris = Vec::new();
    for k in 0..triangles / 2 {
        let c = Vec3::new(rnd(), rnd(), rnd()) * 4.0 - 2.0;
        for _ in 0..4 {
            p.push(c + Vec3::new(rnd(), rnd(), rnd()) * 0.6 - 0.3);
        }
        tris.push([4 * k, 4 * k + 1, 4 * k + 2]);
        tris.push([4 * k + 2, 4 * k + 1, 4 * k + 3]);
    }
    let n = tris.len();
    let vertices = p.len();
    let mesh = Shape::triangles(p, tris, Kept::All(n), None, input(vertices, n)).unwrap();
    let centers: Vec<Vec3> = (0..100)
        .map(|_| Vec3::new(rnd(), rnd(), rnd()) * 4.0 - 2.0)
        .collect();
    let radii = (0..100).map(|_| 0.05 + 0.1 * rnd()).collect();
    let balls = Shape::spheres(centers, radii, (0..100).collect(), input(100, 100)).unwrap();
    let mut placed = [mesh.shape.clone(), balls.shape.clone(), balls.shape].map(|s| {
        PlacedShape::new(
            Arc::new(s),
            SurfaceMaterial::default(),
            Mat4::from_rotation_y(0.3),
        )
    });
    // The same spheres placed as they are: tested in the wide tree's
    // sphere blocks, not one by one.
    placed[2].transform = Mat4::IDENTITY;
    (placed, rnd)
}

#[test]
fn the_bvh_finds_the_nearest_of_many_primitives() {
    // Each ray's answer checked against testing every primitive, in the
    // CPU's wide tree and the GPU's binary one.
    let (placed, mut rnd) = cloud(600);
    let set = ShapeSet::build(&placed).unwrap();
    let binary = ShapeSet::build_binary(&placed).unwrap();
    assert!(set.len() > 780 && set.len() <= 800);
    let mut hits = 0;
    for _ in 0..2000 {
        let o = Vec3::new(rnd(), rnd(), rnd()) * 8.0 - 4.0;
        let d = (Vec3::new(rnd(), rnd(), rnd()) - 0.5).normalize();
        let mut best: Option<(f32, u32, u32)> = None;
        for prim in &set.prims {
            if let Some((t, _)) = set.distance(*prim, o, d, 0.0, f32::INFINITY) {
                if best.is_none_or(|b| t < b.0) {
                    best = Some((t, prim.shape, prim.index));
                }
            }
        }
        for (tree, got) in [
            ("wide", set.hit(o, d, 0.0, f32::INFINITY)),
            ("binary", binary.hit(o, d, 0.0, f32::INFINITY)),
        ] {
            match (got, best) {
                (None, None) => {}
                (Some(h), Some((t, _, _))) => {
                    hits += 1;
                    // The same arithmetic: the same distance.
                    assert_eq!(h.t, t, "{tree}");
                }
                _ => panic!("{tree} BVH {got:?} against every primitive {best:?}"),
            }
        }
    }
    assert!(hits > 200, "{hits} rays hit");
}

/// The wide tree's kernels built for each SIMD level this CPU runs find
/// the same hits to the bit, on a cloud large enough for a tree of
/// several levels.
#[test]
fn every_simd_level_finds_the_same_hits() {
    let (placed, mut rnd) = cloud(20_000);
    let set = ShapeSet::build(&placed).unwrap();
    let levels: Vec<Level> = Level::ALL.into_iter().filter(|l| l.runs()).collect();
    let mut hits = 0;
    for _ in 0..3000 {
        let o = Vec3::new(rnd(), rnd(), rnd()) * 8.0 - 4.0;
        let d = (Vec3::new(rnd(), rnd(), rnd()) - 0.5).normalize();
        let t_min = rnd() * 0.5;
        let reference = set.hit_on(Level::Portable, o, d, t_min, 6.0);
        hits += u32::from(reference.is_some());
        for &level in &levels {
            assert_eq!(set.hit_on(level, o, d, t_min, 6.0), reference, "{level:?}");
        }
    }
    assert!(hits > 500, "{hits} rays hit");
    eprintln!("levels run here: {levels:?}");
}

/// A closed surface lets no ray through: rays aimed at the mesh's shared
/// edges and corners, where a test that computes an edge differently for
/// its two triangles leaves cracks of rounding, all hit it, in the wide
/// tree at every SIMD level and in the GPU's binary one.
#[test]
fn no_ray_slips_between_triangles_that_share_an_edge() {
    // A bumpy grid of 40 x 40 quads over [-1, 1]^2, each split in two,
    // the diagonals alternating, turned off the axes by an instance.
    let n = 40u32;
    let mut rnd = random(11);
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (
                i as f32 / n as f32 * 2.0 - 1.0,
                j as f32 / n as f32 * 2.0 - 1.0,
            );
            p.push(Vec3::new(
                x,
                y,
                0.1 * (3.1 * x).sin() * (2.3 * y).cos() + 0.01 * rnd(),
            ));
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if (i + j) % 2 == 0 {
                tris.extend([[a, b, c], [a, c, d]]);
            } else {
                tris.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
    let turn = Mat4::from_rotation_x(0.37) * Mat4::from_rotation_z(0.21);
    let world: Vec<Vec3> = p.iter().map(|&v| turn.transform_point3(v)).collect();
    let edges: Vec<[Vec3; 2]> = tris
        .iter()
        .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
        .map(|e| e.map(|v| world[v as usize]))
        .collect();
    let (count, vertices) = (tris.len(), p.len());
    let mesh = Shape::triangles(p, tris, Kept::All(count), None, input(vertices, count)).unwrap();
    let placed = [PlacedShape::new(
        Arc::new(mesh.shape),
        SurfaceMaterial::default(),
        turn,
    )];
    let set = ShapeSet::build(&placed).unwrap();
    let binary = ShapeSet::build_binary(&placed).unwrap();
    let levels: Vec<Level> = Level::ALL.into_iter().filter(|l| l.runs()).collect();
    let mut rays = 0;
    for [a, b] in edges {
        // Corners of the grid's rim and points on its rim's edges may be
        // grazed from outside; the points aimed at keep inside it.
        let centre = world[at(n / 2, n / 2) as usize];
        for s in [0.0, 0.25, 0.5, 0.61803] {
            let target = a + (b - a) * s;
            if (target - centre).length() > 0.9 {
                continue;
            }
            // From the side the bumps face and from behind, steep and oblique.
            let from =
                Vec3::new(rnd() - 0.5, rnd() - 0.5, 1.0) * if rnd() < 0.5 { 4.0 } else { -4.0 };
            let o = target + turn.transform_vector3(from);
            let d = target - o;
            rays += 1;
            let every = set
                .prims
                .iter()
                .filter(|p| set.distance(**p, o, d, 0.0, 2.0).is_some())
                .count();
            assert!(
                every > 0,
                "scalar: none of {} for {target}",
                set.prims.len()
            );
            for (tree, hit) in [
                ("wide", set.hit(o, d, 0.0, 2.0)),
                ("binary", binary.hit(o, d, 0.0, 2.0)),
            ] {
                assert!(
                    hit.is_some(),
                    "{tree}: the ray to {target} (s {s}) from {o} slipped through"
                );
            }
            for &level in &levels {
                assert!(
                    set.hit_on(level, o, d, 0.0, 2.0).is_some(),
                    "{level:?}: to {target}"
                );
            }
        }
    }
    assert!(rays > 10_000, "{rays} rays");
}

/// Rays traced eight together find what each finds alone, at every SIMD
/// level: neighbouring rays from one eye (the packet's way down the tree),
/// parallel rays from neighbouring origins, part-filled packets, and rays
/// in every direction (one by one inside).
#[test]
fn packets_find_the_hits_single_rays_find() {
    let (placed, mut rnd) = cloud(20_000);
    let set = ShapeSet::build(&placed).unwrap();
    let levels: Vec<Level> = Level::ALL.into_iter().filter(|l| l.runs()).collect();
    let (mut hits, mut ties) = (0, 0);
    for k in 0..1500 {
        let o = Vec3::new(rnd(), rnd(), rnd()) * 8.0 - 4.0;
        let ahead = (Vec3::new(rnd(), rnd(), rnd()) * 4.0 - 2.0 - o).normalize();
        let spread = [0.002, 0.02, 0.3, 3.0][k % 4];
        let parallel = k % 5 == 0;
        let n = if k % 7 == 0 { 1 + k % PACKET } else { PACKET };
        let rays: Vec<(Vec3, Vec3)> = (0..n)
            .map(|_| {
                let jitter = Vec3::new(rnd(), rnd(), rnd()) - 0.5;
                match parallel {
                    true => (o + jitter * spread, ahead),
                    false => (o, (ahead + jitter * spread).normalize()),
                }
            })
            .collect();
        let t_min = rnd() * 0.3;
        for &level in &levels {
            let together = set.hits_on(level, &rays, t_min, 7.0);
            assert!(together[n..].iter().all(Option::is_none));
            for (i, &(o, d)) in rays.iter().enumerate() {
                let alone = set.hit_on(level, o, d, t_min, 7.0);
                match (together[i], alone) {
                    (None, None) => {}
                    (Some(a), Some(b)) if a == b => hits += 1,
                    // Two primitives at the very same distance: either.
                    (Some(a), Some(b)) if a.t == b.t => ties += 1,
                    (a, b) => panic!("{level:?} ray {i} of {n}: together {a:?}, alone {b:?}"),
                }
            }
        }
    }
    assert!(hits > 3000 && ties * 100 < hits, "{hits} hits, {ties} ties");
}

/// The CPU renderer finds its camera rays' first surfaces in packets:
/// the frame is the one it makes tracing them one by one.
#[test]
fn a_frame_of_packets_is_the_frame_of_single_rays() {
    let (placed, _) = cloud(4000);
    let scene = Scene::of_shapes(placed.to_vec()).unwrap();
    let desc = FrameDesc::new(UVec2::splat(N))
        .with_color(ColorFormat::Rgba32F)
        .with_depth();
    let [together, alone] = [true, false].map(|on| {
        CpuRenderer::new()
            .with_surface_packets(on)
            .render(&scene, &camera().0, &RenderSettings::default(), &desc)
            .unwrap()
    });
    assert_eq!(together.depth, alone.depth);
    let covered = alone
        .depth
        .as_ref()
        .unwrap()
        .iter()
        .filter(|d| d.is_finite())
        .count();
    assert!(
        covered > (N * N / 2) as usize,
        "{covered} pixels show a surface"
    );
    let ssim = crate::render::ssim(&together, &alone).unwrap();
    assert!(ssim > 0.9999, "SSIM {ssim}");
}

/// A direction's components of -0 (as a camera's arithmetic can give)
/// take the tree's boxes from the side their inverse says: such rays hit
/// what rays of +0 components hit, alone and in packets.
#[test]
fn negative_zero_directions_hit_what_positive_zero_ones_hit() {
    let (placed, mut rnd) = cloud(2000);
    let set = ShapeSet::build(&placed).unwrap();
    let mut hits = 0;
    for _ in 0..400 {
        let o = Vec3::new(rnd() * 4.0 - 2.0, rnd() * 4.0 - 2.0, 5.0);
        let plus = set.hit(o, Vec3::new(0.0, 0.0, -1.0), 0.0, 20.0);
        let minus = set.hit(o, Vec3::new(-0.0, -0.0, -1.0), 0.0, 20.0);
        assert_eq!(plus.map(|h| h.t), minus.map(|h| h.t), "from {o}");
        let packet = set.hits(&[(o, Vec3::new(-0.0, -0.0, -1.0)); 2], 0.0, 20.0);
        assert_eq!(packet[0].map(|h| h.t), plus.map(|h| h.t), "from {o}");
        hits += u32::from(plus.is_some());
    }
    assert!(hits > 40, "{hits} rays hit");
}

/// Checks every pixel of the orthographic view down -z that `expect`
/// has an answer for: nothing there (`Some(None)`) or a surface at height
/// z of color c (`Some(Some((z, c)))`); silhouette pixels, which may go
/// either way, it skips (`None`). Returns the pixels of surface checked.
fn check_view(
    frame: &Frame,
    expect: impl Fn(f32, f32) -> Option<Option<(f32, Vec3)>>,
    tolerance: f32,
) -> u32 {
    let depth = frame.depth.clone().unwrap();
    let mut checked = 0;
    for y in 0..N {
        for x in 0..N {
            let (px, py) = centre(x, y);
            let d = depth[(y * N + x) as usize];
            match expect(px, py) {
                None => {}
                Some(None) => assert_eq!(d, f32::INFINITY, "{x},{y}"),
                Some(Some((z, want))) => {
                    checked += 1;
                    assert!((d - (5.0 - z)).abs() < tolerance, "depth at {x},{y}: {d}");
                    let got = frame.pixel(x, y).truncate();
                    assert!(
                        (got - want).abs().max_element() < 1e-3,
                        "{x},{y}: {got} vs {want}"
                    );
                }
            }
        }
    }
    checked
}

fn attribute_material() -> SurfaceMaterial {
    SurfaceMaterial {
        color: ColorSource::Attribute(0),
        opacity: OpacitySource::Constant(1.0),
        alpha: AlphaMode::Opaque,
        pbr: None,
    }
}

/// Half a pixel's width, the band around a silhouette left unchecked.
const HALF_PIXEL: f32 = 2.0 / N as f32;

/// A cone from x = -1.5 to 1.5 of `radii` there, capped at both ends,
/// red at the first end and blue at the second, Lambertian in a headlight.
fn along_x(radii: [f32; 2]) -> Frame {
    let p = vec![Vec3::new(-1.5, 0.0, 0.0), Vec3::new(1.5, 0.0, 0.0)];
    let mut inp = input(2, 1);
    inp.attributes[0] = Some(Attribute::per_vertex(vec![Vec4::X, Vec4::Z]));
    let made = Shape::cones("cone", p, vec![[0, 1]], vec![radii], vec![[true; 2]], inp).unwrap();
    let placed = PlacedShape::new(Arc::new(made.shape), attribute_material(), Mat4::IDENTITY);
    render(&Scene::of_shapes(vec![placed]).unwrap(), &unlit_ambient())
}

#[test]
fn a_cylinder_shows_its_silhouette_depth_and_colors_along_its_axis() {
    let checked = check_view(
        &along_x([0.5, 0.5]),
        |px, py| {
            if px.abs() > 1.5 + HALF_PIXEL || py.abs() > 0.5 + HALF_PIXEL {
                return Some(None);
            }
            if px.abs() > 1.5 - HALF_PIXEL || py.abs() > 0.5 - HALF_PIXEL {
                return None;
            }
            // Red at the first end, blue at the second, lit by the
            // normal's z.
            let z = (0.25 - py * py).sqrt();
            let s = (px + 1.5) / 3.0;
            Some(Some((z, Vec3::new(1.0 - s, 0.0, s) * (z / 0.5))))
        },
        1e-4,
    );
    assert!(checked > 100, "{checked}");
}

#[test]
fn a_cone_narrows_linearly_and_tilts_its_normal() {
    let frame = along_x([0.8, 0.2]);
    let slope = (0.2f32 - 0.8) / 3.0;
    let checked = check_view(
        &frame,
        |px, py| {
            let r = 0.8 + slope * (px + 1.5);
            if px.abs() > 1.5 + HALF_PIXEL || py.abs() > r + HALF_PIXEL {
                return Some(None);
            }
            if px.abs() > 1.5 - HALF_PIXEL || py.abs() > r - HALF_PIXEL {
                return None;
            }
            let z = (r * r - py * py).sqrt();
            let s = (px + 1.5) / 3.0;
            // The normal (radial - slope axis) normalized: its z.
            let nz = (z / r) / (1.0 + slope * slope).sqrt();
            Some(Some((z, Vec3::new(1.0 - s, 0.0, s) * nz)))
        },
        1e-4,
    );
    assert!(checked > 100, "{checked}");
}

#[test]
fn a_straight_curve_is_a_capsule_colored_along_its_vertices() {
    // Three vertices on x, one radius: two segments that read as one
    // capsule, red to green to blue.
    let p = vec![
        Vec3::new(-1.2, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.2, 0.0, 0.0),
    ];
    let mut inp = input(3, 2);
    inp.attributes[0] = Some(Attribute::per_vertex(vec![Vec4::X, Vec4::Y, Vec4::Z]));
    let made = Shape::curves(p, vec![0.5; 3], vec![0, 1], inp).unwrap();
    let placed = PlacedShape::new(Arc::new(made.shape), attribute_material(), Mat4::IDENTITY);
    let frame = render(&Scene::of_shapes(vec![placed]).unwrap(), &unlit_ambient());
    let checked = check_view(
        &frame,
        |px, py| {
            // Distance from the axis segment [-1.2, 1.2] on x.
            let along = px.clamp(-1.2, 1.2);
            let off = ((px - along).powi(2) + py * py).sqrt();
            if off > 0.5 + HALF_PIXEL {
                return Some(None);
            }
            if off > 0.5 - HALF_PIXEL {
                return None;
            }
            let z = (0.25 - off * off).sqrt();
            let s = (along + 1.2) / 1.2;
            let color = if s <= 1.0 {
                Vec3::X.lerp(Vec3::Y, s)
            } else {
                Vec3::Y.lerp(Vec3::Z, s - 1.0)
            };
            Some(Some((z, color * (z / 0.5))))
        },
        1e-4,
    );
    assert!(checked > 100, "{checked}");
    // Out-of-range segments are reported, not rendered.
    let e = Shape::curves(
        vec![Vec3::ZERO, Vec3::X],
        vec![1.0; 2],
        vec![1],
        input(2, 1),
    );
    assert_eq!(
        e.err().unwrap().to_string(),
        "curve segment 0 refers to vertex 2; there are 2 vertices"
    );
}

#[test]
fn a_glossy_sphere_peaks_where_its_normal_halves_light_and_eye() {
    let pbr = crate::scene::Pbr {
        metallic: 1.0,
        roughness: 0.15,
        emissive: Vec3::new(0.0, 0.05, 0.0),
    };
    let mut sphere = unit_sphere(ColorSource::Constant(Vec3::splat(0.9)), Mat4::IDENTITY);
    sphere.material.pbr = Some(pbr);
    let scene = Scene::of_shapes(vec![sphere]).unwrap();
    let towards = Vec3::new(0.5, 0.3, 1.0).normalize();
    let settings = RenderSettings {
        ambient: Vec3::ZERO,
        surface_shading: crate::render::SurfaceShading::Lights,
        headlight: false,
        light: towards,
        ..RenderSettings::default()
    };
    let frame = render(&scene, &settings);
    let mut brightest = (0.0, 0, 0);
    for y in 0..N {
        for x in 0..N {
            let c = frame.pixel(x, y);
            if c.x > brightest.0 {
                brightest = (c.x, x, y);
            }
        }
    }
    // The eye looks down -z: the highlight is where n = (l + v) / |l + v|.
    let h = (towards + Vec3::Z).normalize();
    let (px, py) = centre(brightest.1, brightest.2);
    let pixel = 4.0 / N as f32;
    assert!(
        (px - h.x).abs() <= pixel && (py - h.y).abs() <= pixel,
        "peak at {px},{py}, the mirror point at {},{}",
        h.x,
        h.y
    );
    // Under the eye light the material shows its base color, plus what
    // it emits, as a matte one would.
    let eye = render(&scene, &RenderSettings::default());
    let c = eye.pixel(N / 2, N / 2).truncate();
    assert!(
        (c - Vec3::new(0.9, 0.95, 0.9)).abs().max_element() < 0.01,
        "{c}"
    );
}
