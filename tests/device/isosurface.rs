//! Isosurfaces through ANARI (ANARI_KHR_GEOMETRY_ISOSURFACE): a field, an
//! `isosurface` geometry, a `matte` or `curvature` material and a surface
//! in the world's `surface` array (or a group's), drawn by the CPU
//! reference's caster with the renderer's settings; and the `multiView`
//! camera, whose panel image is, subpixel by subpixel, the interleaving of
//! its views rendered one by one.

use crate::common;

use anari_library_caveray::cave::{MultiViewDisplay, Units, ViewPattern};
use anari_library_caveray::device::{DataType, Input, Property, Severity, StatusCode, Subject};
use anari_library_caveray::geometry::{OffAxisCamera, PrimaryRays, Screen};
use anari_library_caveray::render::iso::{cast, IsoFilter, IsoSettings};
use anari_library_caveray::render::FrameDesc;
use common::device::{bytes, same, Host};
use glam::{DVec3, Mat4, UVec2, Vec3};

/// Vertices a side of the test field.
const N: u32 = 20;
const W: u32 = 40;
const H: u32 = 24;

/// The panel the cameras look through: 1 x 0.6 at z = 0, facing +z.
fn screen() -> Screen {
    Screen::new(
        DVec3::new(-0.5, -0.3, 0.0),
        DVec3::new(0.5, -0.3, 0.0),
        DVec3::new(0.5, 0.3, 0.0),
    )
    .unwrap()
}

/// 1 - |p - centre| on [-1, 1]^3 moved back by 1.2 (behind the panel):
/// the iso-value v is a ball of radius 1 - v around (0, 0, -1.2), with a
/// smaller ball stuck to it so that views differ near the seam.
fn ball_value(p: Vec3) -> f32 {
    let big = 1.0 - p.length();
    let small = 1.0 - 2.0 * (p - Vec3::new(0.35, 0.25, 0.4)).length();
    big.max(small)
}

const ORIGIN: [f32; 3] = [-1.0, -1.0, -2.2];

fn field_voxels() -> Vec<f32> {
    let h = 2.0 / (N - 1) as f32;
    let mut v = Vec::new();
    for z in 0..N {
        for y in 0..N {
            for x in 0..N {
                v.push(ball_value(
                    Vec3::new(x as f32, y as f32, z as f32) * h - Vec3::ONE,
                ));
            }
        }
    }
    v
}

fn field(h: &mut Host) -> u64 {
    let data = h.array(
        DataType::ARRAY3D,
        DataType::FLOAT32,
        [u64::from(N); 3],
        &bytes(&field_voxels()),
    );
    let f = h.d.new_object(DataType::SPATIAL_FIELD, "structuredRegular");
    h.set_object(f, "data", DataType::ARRAY3D, data);
    h.set(f, "origin", DataType::FLOAT32_VEC3, bytes(&ORIGIN));
    let s = 2.0 / (N - 1) as f32;
    h.set(f, "spacing", DataType::FLOAT32_VEC3, bytes(&[s; 3]));
    h.d.commit(Subject::Object(f));
    h.d.release(data);
    f
}

/// The same field as the library's caster takes it.
fn placed() -> anari_library_caveray::scene::PlacedVolume {
    common::iso::field(
        N,
        Mat4::from_translation(Vec3::new(0.0, 0.0, -1.2)),
        ball_value,
    )
}

/// An isosurface of `field` at `isovalues` in a material: (surface,
/// geometry, material).
fn surface(h: &mut Host, field: u64, isovalues: &[f32], material: u64) -> (u64, u64) {
    let g = h.d.new_object(DataType::GEOMETRY, "isosurface");
    h.set_object(g, "field", DataType::SPATIAL_FIELD, field);
    match isovalues {
        [one] => h.set(g, "isovalue", DataType::FLOAT32, bytes(&[*one])),
        many => {
            let a = h.array(
                DataType::ARRAY1D,
                DataType::FLOAT32,
                [many.len() as u64, 1, 1],
                &bytes(many),
            );
            h.set_object(g, "isovalue", DataType::ARRAY1D, a);
            h.d.release(a);
        }
    }
    h.d.commit(Subject::Object(g));
    let s = h.d.new_object(DataType::SURFACE, "");
    h.set_object(s, "geometry", DataType::GEOMETRY, g);
    h.set_object(s, "material", DataType::MATERIAL, material);
    h.d.commit(Subject::Object(s));
    (s, g)
}

fn matte(h: &mut Host, color: [f32; 3]) -> u64 {
    let m = h.d.new_object(DataType::MATERIAL, "matte");
    h.set(m, "color", DataType::FLOAT32_VEC3, bytes(&color));
    h.d.commit(Subject::Object(m));
    m
}

fn world_of(h: &mut Host, kind: DataType, name: &str, objects: &[u64]) -> u64 {
    let handles: Vec<usize> = objects.iter().map(|&o| o as usize).collect();
    let list = h.array(
        DataType::ARRAY1D,
        kind,
        [objects.len() as u64, 1, 1],
        &bytes(&handles),
    );
    let world = h.d.new_object(DataType::WORLD, "");
    h.set_object(world, name, DataType::ARRAY1D, list);
    h.d.commit(Subject::Object(world));
    h.d.release(list);
    world
}

/// The panel's corners as a camera's `lowerLeft`, `lowerRight`,
/// `upperRight`.
fn set_corners(h: &mut Host, camera: u64) {
    let s = screen();
    for (name, p) in [
        ("lowerLeft", s.ll()),
        ("lowerRight", s.lr()),
        ("upperRight", s.ur()),
    ] {
        h.set(
            camera,
            name,
            DataType::FLOAT32_VEC3,
            bytes(&p.as_vec3().to_array()),
        );
    }
}

/// An off-axis camera through the panel from `eye`.
fn off_axis(h: &mut Host, eye: [f32; 3]) -> u64 {
    let c = h.d.new_object(DataType::CAMERA, "offAxis");
    set_corners(h, c);
    h.set(c, "eye", DataType::FLOAT32_VEC3, bytes(&eye));
    h.d.commit(Subject::Object(c));
    c
}

/// A W x H frame of `world` through `camera`, RGBA8 (and depth if asked).
fn frame(h: &mut Host, world: u64, camera: u64, depth: bool) -> u64 {
    let renderer = h.d.new_object(DataType::RENDERER, "default");
    h.d.commit(Subject::Object(renderer));
    let f = h.d.new_object(DataType::FRAME, "");
    h.set(f, "size", DataType::UINT32_VEC2, bytes(&[W, H]));
    h.set(
        f,
        "channel.color",
        DataType::DATA_TYPE,
        bytes(&[DataType::UFIXED8_VEC4 as i32]),
    );
    if depth {
        h.set(
            f,
            "channel.depth",
            DataType::DATA_TYPE,
            bytes(&[DataType::FLOAT32 as i32]),
        );
    }
    h.set_object(f, "world", DataType::WORLD, world);
    h.set_object(f, "renderer", DataType::RENDERER, renderer);
    h.set_object(f, "camera", DataType::CAMERA, camera);
    h.d.commit(Subject::Object(f));
    h.d.release(renderer);
    f
}

/// The depth channel of a rendered frame.
fn depth(h: &mut Host, f: u64) -> Vec<f32> {
    h.depth_sized(f, W, H)
}

/// The world's `bounds` property, to single precision.
fn assert_box(h: &mut Host, world: u64, expected: [f32; 6]) {
    match h.d.property(Subject::Object(world), "bounds", true) {
        Some(Property::Box3(b)) => assert!(
            b.iter().zip(expected).all(|(a, e)| (a - e).abs() < 1e-5),
            "bounds {b:?}, expected {expected:?}"
        ),
        other => panic!("no bounds: {other:?}"),
    }
}

fn at(pixels: &[u8], x: u32, y: u32) -> [u8; 3] {
    let i = 4 * (y * W + x) as usize;
    [pixels[i], pixels[i + 1], pixels[i + 2]]
}

#[test]
fn an_isosurface_through_anari_is_the_casters_image() {
    let mut h = Host::new();
    let f = field(&mut h);
    let m = matte(&mut h, [0.2, 0.6, 0.9]);
    let (s, _) = surface(&mut h, f, &[0.5], m);
    let world = world_of(&mut h, DataType::SURFACE, "surface", &[s]);
    let eye = [0.05f32, 0.02, 2.0];
    let camera = off_axis(&mut h, eye);
    let fr = frame(&mut h, world, camera, true);
    let image = h.pixels_sized(fr, W, H);
    assert!(h.messages(Severity::Error).is_empty());

    // The caster, given what the device documents: trilinear, two steps a
    // cell (step factor 1), a headlight, the renderer's black background.
    let rays = OffAxisCamera::new(screen(), DVec3::new(0.05, 0.02, 2.0))
        .unwrap()
        .ray_gen(UVec2::new(W, H));
    let settings = IsoSettings {
        filter: IsoFilter::Trilinear,
        coloring: anari_library_caveray::render::iso::Coloring::Flat(Vec3::new(0.2, 0.6, 0.9)),
        ..IsoSettings::new(0.5)
    };
    let (expected, hits) = cast(
        &placed(),
        &rays,
        &FrameDesc::new(UVec2::new(W, H)),
        &settings,
    )
    .unwrap();
    let expected = match &expected.color {
        anari_library_caveray::render::ColorData::Rgba8(b) => b.clone(),
        _ => unreachable!("RGBA8 asked for"),
    };
    same(&image, &expected).unwrap();
    assert!(hits.iter().filter(|h| h.is_some()).count() > (W * H / 8) as usize);

    // The ball's front at the middle of the panel: 2.0 from the eye to the
    // panel, 1.2 - 0.5 behind it, along a nearly straight-on ray.
    let d = depth(&mut h, fr);
    let centre = d[(H / 2 * W + W / 2) as usize];
    let expected_depth = (Vec3::new(0.0, 0.0, -0.7) - Vec3::from(eye)).length();
    assert!(
        (centre - expected_depth).abs() < 0.03,
        "centre depth {centre}, expected about {expected_depth}"
    );
    assert_eq!(d[0], f32::INFINITY, "the corner sees past the ball");

    // The world's bounds are the field's.
    assert_box(&mut h, world, [-1.0, -1.0, -2.2, 1.0, 1.0, -0.2]);
}

#[test]
fn the_nearest_of_several_isosurfaces_shows() {
    let mut h = Host::new();
    let f = field(&mut h);
    let red = matte(&mut h, [1.0, 0.0, 0.0]);
    let green = matte(&mut h, [0.0, 1.0, 0.0]);
    // Inner ball (0.8: radius 0.2) red, outer (0.5: radius 0.5) green.
    let (inner, _) = surface(&mut h, f, &[0.8], red);
    let (outer, _) = surface(&mut h, f, &[0.5], green);
    let camera = off_axis(&mut h, [0.0, 0.0, 2.0]);
    let (cx, cy) = (W / 2, H / 2);

    let world = world_of(&mut h, DataType::SURFACE, "surface", &[inner, outer]);
    let fr = frame(&mut h, world, camera, true);
    let both = h.pixels_sized(fr, W, H);
    let [r, g, _] = at(&both, cx, cy);
    // (Both carry the same white highlight.)
    assert!(
        g > r + 100,
        "the outer, green ball hides the red one: {r} {g}"
    );
    let near = depth(&mut h, fr)[(cy * W + cx) as usize];

    let alone = world_of(&mut h, DataType::SURFACE, "surface", &[inner]);
    let fr2 = frame(&mut h, alone, camera, true);
    let inner_only = h.pixels_sized(fr2, W, H);
    let [r, g, _] = at(&inner_only, cx, cy);
    assert!(r > g + 100, "alone, the red ball shows: {r} {g}");
    let far = depth(&mut h, fr2)[(cy * W + cx) as usize];
    assert!(
        (far - near - 0.3).abs() < 0.03,
        "the balls' fronts are 0.3 apart: {near} and {far}"
    );

    // One geometry with both iso-values draws the same as two surfaces.
    let (two, _) = surface(&mut h, f, &[0.8, 0.5], green);
    let world3 = world_of(&mut h, DataType::SURFACE, "surface", &[two]);
    let fr3 = frame(&mut h, world3, camera, false);
    let centre = at(&h.pixels_sized(fr3, W, H), cx, cy);
    assert_eq!(centre, at(&both, cx, cy));
}

#[test]
fn the_curvature_material_colors_a_ball_convex_and_instances_move_surfaces() {
    let mut h = Host::new();
    let f = field(&mut h);
    let m = h.d.new_object(DataType::MATERIAL, "curvature");
    h.set(m, "radius", DataType::FLOAT32, bytes(&[0.5f32]));
    h.d.commit(Subject::Object(m));
    let (s, _) = surface(&mut h, f, &[0.5], m);
    // Through a group and a translating instance: the ball moves 0.3 up.
    let group = h.d.new_object(DataType::GROUP, "");
    let list = h.array(
        DataType::ARRAY1D,
        DataType::SURFACE,
        [1, 1, 1],
        &bytes(&[s as usize]),
    );
    h.set_object(group, "surface", DataType::ARRAY1D, list);
    h.d.commit(Subject::Object(group));
    let instance = h.d.new_object(DataType::INSTANCE, "transform");
    h.set_object(instance, "group", DataType::GROUP, group);
    let up = Mat4::from_translation(Vec3::new(0.0, 0.3, 0.0)).to_cols_array();
    h.set(instance, "transform", DataType::FLOAT32_MAT4, bytes(&up));
    h.d.commit(Subject::Object(instance));
    let world = world_of(&mut h, DataType::INSTANCE, "instance", &[instance]);
    assert_box(&mut h, world, [-1.0, -0.7, -2.2, 1.0, 1.3, -0.2]);
    let camera = off_axis(&mut h, [0.0, 0.0, 2.0]);
    let fr = frame(&mut h, world, camera, false);
    let image = h.pixels_sized(fr, W, H);
    assert!(h.messages(Severity::Error).is_empty());
    // A ball of radius 0.5 under radius 0.5: convex, saturated orange.
    let [r, _, b] = at(&image, W / 2, H / 2 + 4);
    assert!(r > 2 * b.max(1), "convex is orange: r {r} b {b}");
    // Moved up: the bottom rows below the ball see past it.
    assert_eq!(at(&image, W / 2, 1), [0, 0, 0]);
}

#[test]
fn bad_surfaces_are_reported_and_leave_the_device_usable() {
    let mut h = Host::new();
    let f = field(&mut h);
    let g = h.d.new_object(DataType::GEOMETRY, "isosurface");
    h.set(g, "isovalue", DataType::FLOAT32, bytes(&[0.5f32]));
    h.d.commit(Subject::Object(g));
    let e = h.messages(Severity::Error);
    assert!(
        e.iter().any(|m| m.contains("required parameter 'field'")),
        "{e:?}"
    );
    h.set_object(g, "field", DataType::SPATIAL_FIELD, f);
    h.set(g, "isovalue", DataType::FLOAT32, bytes(&[f32::NAN]));
    h.d.commit(Subject::Object(g));
    let e = h.messages(Severity::Error);
    assert!(
        e.iter().any(|m| m.contains("iso-values must be finite")),
        "{e:?}"
    );

    let m = h.d.new_object(DataType::MATERIAL, "curvature");
    h.set(m, "radius", DataType::FLOAT32, bytes(&[-1.0f32]));
    h.d.commit(Subject::Object(m));
    let e = h.messages(Severity::Error);
    assert!(
        e.iter().any(|m| m.contains("radius must be positive")),
        "{e:?}"
    );

    // The surface renders, and says why not, until its parts are fixed.
    let s = h.d.new_object(DataType::SURFACE, "");
    h.set_object(s, "geometry", DataType::GEOMETRY, g);
    h.set_object(s, "material", DataType::MATERIAL, m);
    h.d.commit(Subject::Object(s));
    let world = world_of(&mut h, DataType::SURFACE, "surface", &[s]);
    let camera = off_axis(&mut h, [0.0, 0.0, 2.0]);
    let fr = frame(&mut h, world, camera, false);
    h.d.render_frame(fr, None);
    assert!(h.d.map_frame(fr, "channel.color").is_none());
    let e = h.messages(Severity::Error);
    assert!(
        e.iter()
            .any(|m| m.contains("is not usable: isovalue[0] is NaN")),
        "{e:?}"
    );
    h.set(g, "isovalue", DataType::FLOAT32, bytes(&[0.5f32]));
    h.d.commit(Subject::Object(g));
    h.set(m, "radius", DataType::FLOAT32, bytes(&[0.5f32]));
    h.d.commit(Subject::Object(m));
    assert_eq!(h.pixels_sized(fr, W, H).len(), (4 * W * H) as usize);

    // A world of volumes and surfaces is refused by name.
    let volume = h.volume(f);
    h.d.commit(Subject::Object(volume));
    let vlist = h.array(
        DataType::ARRAY1D,
        DataType::VOLUME,
        [1, 1, 1],
        &bytes(&[volume as usize]),
    );
    h.set_object(world, "volume", DataType::ARRAY1D, vlist);
    h.d.commit(Subject::Object(world));
    h.d.render_frame(fr, None);
    assert!(h.d.map_frame(fr, "channel.color").is_none());
    let e = h.messages(Severity::Error);
    assert!(
        e.iter()
            .any(|m| m.contains("holds isosurfaces beside volumes")),
        "{e:?}"
    );

    // A deadline frame warps volume images only.
    h.d.unset_param(Subject::Object(world), "volume");
    h.d.commit(Subject::Object(world));
    h.set(fr, "caveray.deadline", DataType::FLOAT32, bytes(&[20.0f32]));
    h.d.commit(Subject::Object(fr));
    h.d.render_frame(fr, None);
    let e = h.messages(Severity::Error);
    assert!(e.iter().any(|m| m.contains("warps volume images")), "{e:?}");
}

/// The display the multi-view tests use: 8 views, the shipped monitor's lens.
fn display(size: UVec2) -> MultiViewDisplay {
    MultiViewDisplay {
        name: "test".into(),
        units: Units::Metres,
        screen: screen(),
        resolution: size,
        views: 8,
        pattern: ViewPattern::Lens {
            pitch: 3.75,
            slant: 0.15625,
            offset: 0.0,
        },
        viewing_distance: 2.0,
        view_spacing: 0.05,
    }
}

/// A multi-view camera of `display()`; `view` -1 for the panel image.
fn multi_view(h: &mut Host, view: i32, method: &str) -> u64 {
    let c = h.d.new_object(DataType::CAMERA, "multiView");
    set_corners(h, c);
    h.set(c, "views", DataType::INT32, bytes(&[8i32]));
    h.set(c, "viewingDistance", DataType::FLOAT32, bytes(&[2.0f32]));
    h.set(c, "viewSpacing", DataType::FLOAT32, bytes(&[0.05f32]));
    h.set(c, "lens.pitch", DataType::FLOAT32, bytes(&[3.75f32]));
    h.set(c, "lens.slant", DataType::FLOAT32, bytes(&[0.15625f32]));
    h.set(c, "view", DataType::INT32, bytes(&[view]));
    h.d.set_param(Subject::Object(c), "method", Input::String(method.into()));
    h.d.commit(Subject::Object(c));
    c
}

/// Every view's image through the camera's `view`, interleaved by the
/// display's pattern: what the panel image must be.
fn interleaved_views(h: &mut Host, world: u64) -> Vec<u8> {
    let views: Vec<Vec<u8>> = (0..8)
        .map(|v| {
            let c = multi_view(h, v, "passes");
            let fr = frame(h, world, c, false);
            h.pixels_sized(fr, W, H)
        })
        .collect();
    let d = display(UVec2::new(W, H));
    let mut out = vec![255u8; (4 * W * H) as usize];
    for y in 0..H {
        for x in 0..W {
            let i = 4 * (y * W + x) as usize;
            for c in 0..3 {
                out[i + c] = views[d.view_of(x, y, c) as usize][i + c];
            }
        }
    }
    out
}

fn panel(h: &mut Host, world: u64, method: &str) -> Vec<u8> {
    let c = multi_view(h, -1, method);
    let fr = frame(h, world, c, false);
    h.pixels_sized(fr, W, H)
}

#[test]
fn the_multi_view_panel_is_its_views_interleaved_subpixel_by_subpixel() {
    let mut h = Host::new();
    let f = field(&mut h);
    let m = matte(&mut h, [0.9, 0.8, 0.6]);
    let (s, _) = surface(&mut h, f, &[0.5], m);
    let world = world_of(&mut h, DataType::SURFACE, "surface", &[s]);
    let naive = interleaved_views(&mut h, world);
    // Views differ: the panel is not one view's image.
    assert!(naive.chunks(4).any(|p| p[0] != p[1] || p[1] != p[2]));

    same(&panel(&mut h, world, "perSubpixel"), &naive).unwrap();
    same(&panel(&mut h, world, "naive"), &naive).unwrap();
    // The passes search red's and blue's rays from where their views'
    // samples met the surface: off by more than 2 levels on few.
    let off = |image: &[u8]| {
        image
            .chunks(4)
            .zip(naive.chunks(4))
            .flat_map(|(a, b)| (0..3).map(move |c| a[c].abs_diff(b[c])))
            .filter(|&d| d > 2)
            .count()
    };
    let passes = off(&panel(&mut h, world, "passes"));
    let all = (3 * W * H) as usize;
    assert!(
        passes * 50 < all,
        "{passes} of {all} subpixels differ by more than 2 levels"
    );
    // Green's hit shaded for red and blue: its green subpixels are the
    // exact ones, the others show green's point and are off more often.
    let shared = panel(&mut h, world, "greenGeometry");
    let green_off = shared
        .chunks(4)
        .zip(naive.chunks(4))
        .filter(|(a, b)| a[1].abs_diff(b[1]) > 2)
        .count();
    assert!(green_off * 200 < all, "{green_off} green subpixels differ");
    assert!(off(&shared) > passes, "{} vs {passes}", off(&shared));
    assert!(h.messages(Severity::Error).is_empty());
}

#[test]
fn a_volume_on_a_multi_view_panel_is_its_views_interleaved() {
    let mut h = Host::new();
    let f = field(&mut h);
    let volume = h.volume(f);
    h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.4f32]));
    h.d.commit(Subject::Object(volume));
    let world = world_of(&mut h, DataType::VOLUME, "volume", &[volume]);
    let naive = interleaved_views(&mut h, world);
    same(&panel(&mut h, world, "passes"), &naive).unwrap();
}

#[test]
fn a_view_table_assigns_each_subpixel_its_view() {
    let mut h = Host::new();
    let f = field(&mut h);
    let m = matte(&mut h, [0.9, 0.8, 0.6]);
    let (s, _) = surface(&mut h, f, &[0.5], m);
    let world = world_of(&mut h, DataType::SURFACE, "surface", &[s]);
    // A period of 2 x 1 pixels: views 0 1 2 | 5 6 7.
    let table: [u8; 6] = [0, 1, 2, 5, 6, 7];
    let c = multi_view(&mut h, -1, "perSubpixel");
    h.d.unset_param(Subject::Object(c), "lens.pitch");
    let a = h.array(DataType::ARRAY2D, DataType::UINT8_VEC3, [2, 1, 1], &table);
    h.set_object(c, "viewTable", DataType::ARRAY2D, a);
    h.d.commit(Subject::Object(c));
    let fr = frame(&mut h, world, c, false);
    let image = h.pixels_sized(fr, W, H);
    assert!(h.messages(Severity::Error).is_empty());
    let views: Vec<Vec<u8>> = (0..8)
        .map(|v| {
            let c = multi_view(&mut h, v, "passes");
            let fr = frame(&mut h, world, c, false);
            h.pixels_sized(fr, W, H)
        })
        .collect();
    let follows = |image: &[u8], table: &[u8; 6]| {
        for y in 0..H {
            for x in 0..W {
                let i = 4 * (y * W + x) as usize;
                for ch in 0..3 {
                    let v = table[3 * (x as usize % 2) + ch] as usize;
                    assert_eq!(
                        image[i + ch],
                        views[v][i + ch],
                        "pixel ({x}, {y}) channel {ch} of view {v}"
                    );
                }
            }
        }
    };
    follows(&image, &table);
    // The device keeps a panel's table between frames: a new pattern on
    // the same camera must replace it.
    let turned: [u8; 6] = [7, 6, 5, 2, 1, 0];
    let a = h.array(DataType::ARRAY2D, DataType::UINT8_VEC3, [2, 1, 1], &turned);
    h.set_object(c, "viewTable", DataType::ARRAY2D, a);
    h.d.commit(Subject::Object(c));
    let fr = frame(&mut h, world, c, false);
    follows(&h.pixels_sized(fr, W, H), &turned);
    assert!(h.messages(Severity::Error).is_empty());
}

#[test]
fn bad_multi_view_cameras_are_reported_by_name() {
    let mut h = Host::new();
    let cases: [(&str, DataType, Vec<u8>, &str); 4] = [
        (
            "views",
            DataType::INT32,
            bytes(&[0i32]),
            "views must be 1 to 64",
        ),
        (
            "view",
            DataType::INT32,
            bytes(&[8i32]),
            "view 8 is not one of the 8 views",
        ),
        (
            "viewSpacing",
            DataType::FLOAT32,
            bytes(&[0.0f32]),
            "viewSpacing must be positive",
        ),
        (
            "viewingDistance",
            DataType::FLOAT32,
            bytes(&[-2.0f32]),
            "viewingDistance must be positive",
        ),
    ];
    for (name, ty, value, message) in cases {
        let c = multi_view(&mut h, -1, "passes");
        assert!(h.messages(Severity::Error).is_empty());
        h.set(c, name, ty, value);
        h.d.commit(Subject::Object(c));
        let e = h.messages(Severity::Error);
        assert!(e.iter().any(|m| m.contains(message)), "{name}: {e:?}");
    }
    // Eyes out of sight of the panel (blank before), a panel in one view
    // (view 0 everywhere before). The panel is 1 wide.
    let far: [(&str, f32, &str); 5] = [
        (
            "viewingDistance",
            1e30,
            "viewingDistance must be from 0.01 to 100 panel widths (0.01 to 100 for this panel), got 1e30",
        ),
        (
            "viewSpacing",
            1e30,
            "viewSpacing times views - 1 (the line of eyes) must be at most 100 panel widths (100 for this panel), got 1e30",
        ),
        (
            "lens.pitch",
            1e-38,
            "lens.pitch must be from 0.015625 to 10000 subpixels, got 1e-38",
        ),
        (
            "lens.pitch",
            1e30,
            "lens.pitch must be from 0.015625 to 10000 subpixels, got 1e30",
        ),
        (
            "lens.slant",
            1e30,
            "lens.slant must be from -10 to 10, got 1e30",
        ),
    ];
    for (name, value, message) in far {
        let c = multi_view(&mut h, -1, "passes");
        assert!(h.errors().is_empty());
        h.set(c, name, DataType::FLOAT32, bytes(&[value]));
        h.d.commit(Subject::Object(c));
        let e = h.errors();
        assert!(
            e.len() == 1 && e[0].0 == StatusCode::InvalidArgument && e[0].1.contains(message),
            "{name} {value}: {e:?}"
        );
    }
    // The ends of the ranges are taken.
    for (name, value) in [
        ("viewingDistance", 0.011f32),
        ("viewingDistance", 100.0),
        ("viewSpacing", 100.0 / 7.0),
        ("lens.pitch", 1.0),
        ("lens.pitch", 10000.0),
        ("lens.slant", -10.0),
    ] {
        let c = multi_view(&mut h, -1, "passes");
        h.set(c, name, DataType::FLOAT32, bytes(&[value]));
        h.d.commit(Subject::Object(c));
        let e = h.errors();
        assert!(e.is_empty(), "{name} {value}: {e:?}");
    }
    let c = multi_view(&mut h, -1, "passes");
    let a = h.array(
        DataType::ARRAY2D,
        DataType::UINT8_VEC3,
        [1, 1, 1],
        &[0, 1, 9],
    );
    h.set_object(c, "viewTable", DataType::ARRAY2D, a);
    h.d.commit(Subject::Object(c));
    let e = h.messages(Severity::Error);
    assert!(e.iter().any(|m| m.contains("not both")), "{e:?}");
    h.d.unset_param(Subject::Object(c), "lens.pitch");
    h.d.commit(Subject::Object(c));
    let e = h.messages(Severity::Error);
    assert!(
        e.iter().any(|m| m.contains("viewTable[0] is [0, 1, 9]")),
        "{e:?}"
    );

    // A panel image has no depth channel; the device says so at render.
    let f = field(&mut h);
    let m = matte(&mut h, [1.0; 3]);
    let (s, _) = surface(&mut h, f, &[0.5], m);
    let world = world_of(&mut h, DataType::SURFACE, "surface", &[s]);
    let c = multi_view(&mut h, -1, "passes");
    let fr = frame(&mut h, world, c, true);
    h.d.render_frame(fr, None);
    let e = h.messages(Severity::Error);
    assert!(
        e.iter().any(|m| m.contains("has no depth channel")),
        "{e:?}"
    );
}

#[test]
fn a_matte_color_by_attribute_name_is_drawn_in_the_default_color() {
    // The conformance tests' matte materials name the `color` attribute;
    // an isosurface has none.
    let mut h = Host::new();
    let f = field(&mut h);
    let m = h.d.new_object(DataType::MATERIAL, "matte");
    h.d.set_param(Subject::Object(m), "color", Input::String("color".into()));
    h.d.commit(Subject::Object(m));
    assert!(h.messages(Severity::Error).is_empty());
    let (s, _) = surface(&mut h, f, &[0.25, 0.5, 0.75], m);
    let world = world_of(&mut h, DataType::SURFACE, "surface", &[s]);
    let camera = off_axis(&mut h, [0.0, 0.0, 2.0]);
    let fr = frame(&mut h, world, camera, false);
    let image = h.pixels_sized(fr, W, H);
    assert!(h.messages(Severity::Error).is_empty());
    // The default matte color is grey: the lit surface has r = g = b.
    let [r, g, b] = at(&image, W / 2, H / 2);
    assert!(r > 50 && r == g && g == b, "{r} {g} {b}");
}

/// Where the rays miss an isosurface, a background image shows (here a
/// bottom-to-top gradient), on both renderers; the surface stays as it was.
#[test]
fn a_background_image_shows_around_an_isosurface() {
    for backend in ["cpu", "gpu"] {
        let mut h = Host::on_backend(backend, std::sync::Arc::new(|_s| {}));
        let f = field(&mut h);
        let m = matte(&mut h, [0.2, 0.6, 0.9]);
        let (s, _) = surface(&mut h, f, &[0.5], m);
        let world = world_of(&mut h, DataType::SURFACE, "surface", &[s]);
        let camera = off_axis(&mut h, [0.05, 0.02, 2.0]);
        let fr = frame(&mut h, world, camera, false);
        let plain = h.pixels_sized(fr, W, H);
        let r = h.d.new_object(DataType::RENDERER, "default");
        let gradient = h.array(
            DataType::ARRAY1D,
            DataType::FLOAT32_VEC4,
            [2, 1, 1],
            &bytes(&[1.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0]),
        );
        h.set_object(r, "background", DataType::ARRAY1D, gradient);
        h.d.commit(Subject::Object(r));
        h.set_object(fr, "renderer", DataType::RENDERER, r);
        h.d.commit(Subject::Object(fr));
        let over = h.pixels_sized(fr, W, H);
        assert!(h.messages(Severity::Error).is_empty(), "{backend}");
        let centre = (H / 2 * W + W / 2) as usize;
        assert_eq!(
            &over[4 * centre..4 * centre + 4],
            &plain[4 * centre..4 * centre + 4],
            "{backend}: the surface changed"
        );
        assert_eq!(at(&over, 0, 0), [255, 0, 0], "{backend}: bottom corner");
        assert_eq!(at(&over, 0, H - 1), [0, 0, 255], "{backend}: top corner");
        h.d.release(gradient);
    }
}

#[test]
fn an_isosurface_world_refuses_hit_channels_by_name() {
    let mut h = Host::new();
    let f = field(&mut h);
    let m = matte(&mut h, [0.2, 0.6, 0.9]);
    let (s, _) = surface(&mut h, f, &[0.5], m);
    let world = world_of(&mut h, DataType::SURFACE, "surface", &[s]);
    let camera = off_axis(&mut h, [0.05, 0.02, 2.0]);
    let fr = frame(&mut h, world, camera, false);
    h.set(
        fr,
        "channel.objectId",
        DataType::DATA_TYPE,
        bytes(&[DataType::UINT32 as i32]),
    );
    h.d.commit(Subject::Object(fr));
    h.d.render_frame(fr, None);
    assert!(h.d.map_frame(fr, "channel.color").is_none());
    let errors = h.messages(Severity::Error);
    assert!(
        errors
            .iter()
            .any(|e| e.contains("whose frames have color and depth channels only")),
        "{errors:?}"
    );
}
