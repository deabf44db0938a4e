//! Surfaces of primitives through ANARI (ANARI_KHR_GEOMETRY_TRIANGLE,
//! _QUAD, _SPHERE, _CYLINDER, _CONE, _CURVE): geometries as hosts build them, colored by a matte
//! material's constant or by attributes, alone or inside a volume, with
//! degenerate input reported at commit, on either backend.

use crate::common;

use anari_library_caveray::device::{DataType, Input, Severity, StatusCode, Subject};
use common::device::{bytes, same, Host, SIZE};

/// A perspective frame from (0, 0, 3) of `surfaces` (and `volume`, if
/// any), its renderer without ambient light, depth kept.
fn frame(h: &mut Host, surfaces: &[u64], volume: Option<u64>) -> u64 {
    frame_of(h, "default", surfaces, volume, &[])
}

/// `frame`, its world lit by `lights` under the `directLight` renderer.
fn lit_frame(h: &mut Host, surfaces: &[u64], volume: Option<u64>, lights: &[u64]) -> u64 {
    frame_of(h, "directLight", surfaces, volume, lights)
}

/// A frame by renderer `subtype` of `surfaces` (and `volume`) in a world
/// of `lights`.
fn frame_of(
    h: &mut Host,
    subtype: &str,
    surfaces: &[u64],
    volume: Option<u64>,
    lights: &[u64],
) -> u64 {
    let world = h.d.new_object(DataType::WORLD, "");
    if !lights.is_empty() {
        h.set_objects(world, "light", DataType::LIGHT, lights);
    }
    h.set_objects(world, "surface", DataType::SURFACE, surfaces);
    if let Some(v) = volume {
        h.d.commit(Subject::Object(v));
        h.set_objects(world, "volume", DataType::VOLUME, &[v]);
    }
    h.d.commit(Subject::Object(world));
    let frame = frame_for(h, subtype, world);
    h.d.release(world);
    frame
}

/// A frame of `world` by renderer `subtype`, from (0, 0, 3).
fn frame_for(h: &mut Host, subtype: &str, world: u64) -> u64 {
    let renderer = h.d.new_object(DataType::RENDERER, subtype);
    h.set(
        renderer,
        "ambientRadiance",
        DataType::FLOAT32,
        bytes(&[0.0f32]),
    );
    h.d.commit(Subject::Object(renderer));
    let camera = h.d.new_object(DataType::CAMERA, "perspective");
    h.set(
        camera,
        "position",
        DataType::FLOAT32_VEC3,
        bytes(&[0.0f32, 0.0, 3.0]),
    );
    h.d.commit(Subject::Object(camera));
    let frame = h.d.new_object(DataType::FRAME, "");
    h.set(frame, "size", DataType::UINT32_VEC2, bytes(&[SIZE, SIZE]));
    h.set(
        frame,
        "channel.color",
        DataType::DATA_TYPE,
        bytes(&[DataType::UFIXED8_VEC4 as i32]),
    );
    h.set(
        frame,
        "channel.depth",
        DataType::DATA_TYPE,
        bytes(&[DataType::FLOAT32 as i32]),
    );
    h.set_object(frame, "world", DataType::WORLD, world);
    h.set_object(frame, "renderer", DataType::RENDERER, renderer);
    h.set_object(frame, "camera", DataType::CAMERA, camera);
    h.d.commit(Subject::Object(frame));
    for o in [renderer, camera] {
        h.d.release(o);
    }
    frame
}

fn matte(h: &mut Host, color: Input) -> u64 {
    let m = h.d.new_object(DataType::MATERIAL, "matte");
    h.d.set_param(Subject::Object(m), "color", color);
    h.d.commit(Subject::Object(m));
    m
}

fn surface(h: &mut Host, geometry: u64, material: u64) -> u64 {
    let s = h.d.new_object(DataType::SURFACE, "");
    h.set_object(s, "geometry", DataType::GEOMETRY, geometry);
    h.set_object(s, "material", DataType::MATERIAL, material);
    h.d.commit(Subject::Object(s));
    s
}

fn vec3_array(h: &mut Host, name: &str, geometry: u64, values: &[[f32; 3]]) {
    let a = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32_VEC3,
        [values.len() as u64, 1, 1],
        &bytes(values),
    );
    h.set_object(geometry, name, DataType::ARRAY1D, a);
    h.d.release(a);
}

fn pixel(p: &[u8], x: u32, y: u32) -> [u8; 4] {
    let i = (4 * (y * SIZE + x)) as usize;
    [p[i], p[i + 1], p[i + 2], p[i + 3]]
}

/// A sphere of radius 0.5 at the origin.
fn sphere(h: &mut Host) -> u64 {
    let g = h.d.new_object(DataType::GEOMETRY, "sphere");
    vec3_array(h, "vertex.position", g, &[[0.0, 0.0, 0.0]]);
    h.set(g, "radius", DataType::FLOAT32, bytes(&[0.5f32]));
    h.d.commit(Subject::Object(g));
    g
}

#[test]
fn a_sphere_shows_its_material_color_facing_the_eye_and_its_depth() {
    let mut h = Host::new();
    let g = sphere(&mut h);
    let m = matte(
        &mut h,
        Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[1.0f32, 0.0, 0.0])),
    );
    let s = surface(&mut h, g, m);
    let f = frame(&mut h, &[s], None);
    let p = h.pixels(f);
    let depth = h.depth_sized(f, SIZE, SIZE);
    assert!(h.errors().is_empty());
    let c = SIZE / 2;
    // Lit from the eye (the world has no light): full color head-on.
    let centre = pixel(&p, c, c);
    assert!(
        centre[0] >= 250 && centre[1] == 0 && centre[2] == 0,
        "{centre:?}"
    );
    // The eye is 3 from the centre; the ray through the pixel just off
    // the axis meets the sphere a little past 2.5.
    let d = depth[(c * SIZE + c) as usize];
    assert!((d - 2.5).abs() < 0.01, "{d}");
    assert_eq!(pixel(&p, 0, 0), [0, 0, 0, 255]);
    assert_eq!(depth[0], f32::INFINITY);
}

#[test]
fn quads_take_per_primitive_colors_and_triangles_per_vertex_ones() {
    let mut h = Host::new();
    // Two quads side by side at z = 0: left red, right blue.
    let g = h.d.new_object(DataType::GEOMETRY, "quad");
    let corners = [
        [-2.0, -2.0, 0.0],
        [0.0, -2.0, 0.0],
        [0.0, 2.0, 0.0],
        [-2.0, 2.0, 0.0],
        [2.0, -2.0, 0.0],
        [2.0, 2.0, 0.0],
    ];
    vec3_array(&mut h, "vertex.position", g, &corners);
    let index = h.array(
        DataType::ARRAY1D,
        DataType::UINT32_VEC4,
        [2, 1, 1],
        &bytes(&[0u32, 1, 2, 3, 1, 4, 5, 2]),
    );
    h.set_object(g, "primitive.index", DataType::ARRAY1D, index);
    let colors = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32_VEC4,
        [2, 1, 1],
        &bytes(&[1.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0]),
    );
    h.set_object(g, "primitive.color", DataType::ARRAY1D, colors);
    h.d.commit(Subject::Object(g));
    let m = matte(&mut h, Input::String("color".into()));
    let s = surface(&mut h, g, m);
    let f = frame(&mut h, &[s], None);
    let p = h.pixels(f);
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    let (left, right) = (pixel(&p, 3, SIZE / 2), pixel(&p, SIZE - 4, SIZE / 2));
    assert!(left[0] > 200 && left[2] == 0, "{left:?}");
    assert!(right[2] > 200 && right[0] == 0, "{right:?}");

    // One triangle soup, green at every corner but the top's white.
    let t = h.d.new_object(DataType::GEOMETRY, "triangle");
    vec3_array(
        &mut h,
        "vertex.position",
        t,
        &[[-3.0, -3.0, 0.0], [3.0, -3.0, 0.0], [0.0, 3.0, 0.0]],
    );
    let colors = h.array(
        DataType::ARRAY1D,
        DataType::UFIXED8_VEC4,
        [3, 1, 1],
        &[0u8, 255, 0, 255, 0, 255, 0, 255, 255, 255, 255, 255],
    );
    h.set_object(t, "vertex.color", DataType::ARRAY1D, colors);
    h.d.commit(Subject::Object(t));
    let s2 = surface(&mut h, t, m);
    let f2 = frame(&mut h, &[s2], None);
    let p = h.pixels(f2);
    // Red grows from the bottom row to the top.
    let (low, high) = (pixel(&p, SIZE / 2, 1), pixel(&p, SIZE / 2, SIZE - 2));
    assert!(low[1] > 200 && high[1] > 200, "{low:?} {high:?}");
    assert!(high[0] > low[0] + 40, "{low:?} {high:?}");
    for o in [g, m, s, f, index, colors, t, s2, f2] {
        h.d.release(o);
    }
}

#[test]
fn bad_geometry_is_an_error_at_commit_and_flat_triangles_a_warning() {
    let mut h = Host::new();
    let t = h.d.new_object(DataType::GEOMETRY, "triangle");
    vec3_array(
        &mut h,
        "vertex.position",
        t,
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [2.0, 0.0, 0.0],
        ],
    );
    let index = h.array(
        DataType::ARRAY1D,
        DataType::UINT32_VEC3,
        [2, 1, 1],
        &bytes(&[0u32, 1, 2, 0, 1, 9]),
    );
    h.set_object(t, "primitive.index", DataType::ARRAY1D, index);
    h.d.commit(Subject::Object(t));
    let errors = h.errors();
    assert!(
        errors
            .iter()
            .any(|(code, m)| *code == StatusCode::InvalidArgument
                && m.contains("primitive 1 refers to vertex 9; there are 4 vertices")),
        "{errors:?}"
    );
    // A line is no triangle: it is dropped, and the host hears so.
    let line = h.array(
        DataType::ARRAY1D,
        DataType::UINT32_VEC3,
        [2, 1, 1],
        &bytes(&[0u32, 1, 2, 0, 1, 3]),
    );
    h.set_object(t, "primitive.index", DataType::ARRAY1D, line);
    h.d.commit(Subject::Object(t));
    assert!(h.errors().is_empty());
    let warnings = h.messages(Severity::Warning);
    assert!(
        warnings
            .iter()
            .any(|m| m.contains("1 triangles of zero area dropped")),
        "{warnings:?}"
    );
    // Curvature needs a field.
    let g = sphere(&mut h);
    let c = h.d.new_object(DataType::MATERIAL, "curvature");
    h.set(c, "radius", DataType::FLOAT32, bytes(&[1.0f32]));
    h.d.commit(Subject::Object(c));
    let s = surface(&mut h, g, c);
    let f = frame(&mut h, &[s], None);
    h.d.render_frame(f, None);
    h.d.frame_ready(f);
    let said: Vec<String> = h.errors().into_iter().map(|(_, m)| m).collect();
    assert!(
        said.iter().any(|m| m.contains("colors isosurfaces only")),
        "{said:?}"
    );
}

#[test]
fn a_sphere_inside_a_volume_hides_what_lies_behind_it() {
    let mut h = Host::new();
    let field = h.field(|_| 0.5, None);
    let volume = h.volume(field);
    let alone = {
        let (f, _) = h.frame(volume, 3.0);
        let p = h.pixels(f);
        h.d.release(f);
        p
    };
    let g = sphere(&mut h);
    let m = matte(
        &mut h,
        Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[1.0f32, 1.0, 0.0])),
    );
    let s = surface(&mut h, g, m);
    let f = frame(&mut h, &[s], Some(volume));
    let p = h.pixels(f);
    let depth = h.depth_sized(f, SIZE, SIZE);
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    let c = SIZE / 2;
    let (with, without) = (pixel(&p, c, c), pixel(&alone, c, c));
    // The yellow sphere shows through the volume in front of it.
    assert!(
        with[0] > without[0] + 30 && with[1] > without[1] + 30,
        "{with:?} vs {without:?}"
    );
    assert!(depth[(c * SIZE + c) as usize] <= 2.5 + 0.01);
    // Beside the sphere the volume is as it is alone.
    assert_eq!(pixel(&p, 2, c), pixel(&alone, 2, c));
}

#[test]
fn cylinders_take_per_primitive_radii_and_warn_of_unknown_caps() {
    let mut h = Host::new();
    let g = h.d.new_object(DataType::GEOMETRY, "cylinder");
    // A thick one across the centre, a thin one above, one of zero length.
    vec3_array(
        &mut h,
        "vertex.position",
        g,
        &[
            [-2.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [-2.0, 0.8, 0.0],
            [2.0, 0.8, 0.0],
            [0.0, -0.8, 0.0],
            [0.0, -0.8, 0.0],
        ],
    );
    let radii = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32,
        [3, 1, 1],
        &bytes(&[0.3f32, 0.02, 0.5]),
    );
    h.set_object(g, "primitive.radius", DataType::ARRAY1D, radii);
    h.d.set_param(Subject::Object(g), "caps", Input::String("lids".into()));
    h.d.commit(Subject::Object(g));
    let warnings = h.messages(Severity::Warning);
    assert!(
        warnings
            .iter()
            .any(|m| m.contains("caps 'lids' is not one of")),
        "{warnings:?}"
    );
    assert!(
        warnings
            .iter()
            .any(|m| m.contains("1 cylinders of zero length or invalid radius dropped")),
        "{warnings:?}"
    );
    let m = matte(
        &mut h,
        Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[0.0f32, 0.0, 1.0])),
    );
    let s = surface(&mut h, g, m);
    let f = frame(&mut h, &[s], None);
    let p = h.pixels(f);
    let depth = h.depth_sized(f, SIZE, SIZE);
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    let c = SIZE / 2;
    assert!(pixel(&p, c, c)[2] > 240, "{:?}", pixel(&p, c, c));
    // The eye is 3 from the axis, the radius 0.3.
    let d = depth[(c * SIZE + c) as usize];
    assert!((d - 2.7).abs() < 0.02, "{d}");
    // The zero-length one at y = -0.8 draws nothing.
    assert_eq!(pixel(&p, c, 6), [0, 0, 0, 255]);
}

fn f32_array(h: &mut Host, name: &str, geometry: u64, values: &[f32]) {
    let a = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32,
        [values.len() as u64, 1, 1],
        &bytes(values),
    );
    h.set_object(geometry, name, DataType::ARRAY1D, a);
    h.d.release(a);
}

fn u8_array(h: &mut Host, name: &str, geometry: u64, values: &[u8]) {
    let a = h.array(
        DataType::ARRAY1D,
        DataType::UINT8,
        [values.len() as u64, 1, 1],
        values,
    );
    h.set_object(geometry, name, DataType::ARRAY1D, a);
    h.d.release(a);
}

/// The depth at the centre of a frame of `geometry` in blue.
fn centre_depth(h: &mut Host, geometry: u64) -> f32 {
    let m = matte(
        h,
        Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[0.0f32, 0.0, 1.0])),
    );
    let s = surface(h, geometry, m);
    let f = frame(h, &[s], None);
    h.pixels(f);
    let depth = h.depth_sized(f, SIZE, SIZE);
    let c = SIZE / 2;
    depth[(c * SIZE + c) as usize]
}

#[test]
fn cones_take_radii_per_vertex_and_caps_per_vertex_over_the_global_caps() {
    let mut h = Host::new();
    // Down the view axis: wide (0.5) at z = 0.5, narrower (0.3) at z = -0.5.
    let g = h.d.new_object(DataType::GEOMETRY, "cone");
    vec3_array(
        &mut h,
        "vertex.position",
        g,
        &[[0.0, 0.0, 0.5], [0.0, 0.0, -0.5]],
    );
    f32_array(&mut h, "vertex.radius", g, &[0.5, 0.3]);
    h.d.set_param(Subject::Object(g), "caps", Input::String("first".into()));
    h.d.commit(Subject::Object(g));
    // The near disc faces the eye at 3.
    let d = centre_depth(&mut h, g);
    assert!((d - 2.5).abs() < 0.01, "{d}");
    // vertex.cap wins over caps: open at the near end, the eye looks in
    // through it at the far disc.
    u8_array(&mut h, "vertex.cap", g, &[0, 1]);
    h.d.commit(Subject::Object(g));
    let d = centre_depth(&mut h, g);
    assert!((d - 3.5).abs() < 0.01, "{d}");
    // Open at both ends, the ray leaves through the narrow end.
    u8_array(&mut h, "vertex.cap", g, &[0, 0]);
    h.d.commit(Subject::Object(g));
    assert_eq!(centre_depth(&mut h, g), f32::INFINITY);
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    // Too few caps, or an end past the vertices: errors at commit.
    u8_array(&mut h, "vertex.cap", g, &[1]);
    h.d.commit(Subject::Object(g));
    let errors = h.errors();
    assert!(
        errors
            .iter()
            .any(|(code, m)| *code == StatusCode::InvalidArgument
                && m.contains("vertex.cap has 1 values for 2 vertices")),
        "{errors:?}"
    );
    let index = h.array(
        DataType::ARRAY1D,
        DataType::UINT32_VEC2,
        [1, 1, 1],
        &bytes(&[0u32, 5]),
    );
    h.set_object(g, "primitive.index", DataType::ARRAY1D, index);
    h.d.release(index);
    u8_array(&mut h, "vertex.cap", g, &[1, 1]);
    h.d.commit(Subject::Object(g));
    let errors = h.errors();
    assert!(
        errors
            .iter()
            .any(|(_, m)| m.contains("cone 0 refers to vertex 5; there are 2 vertices")),
        "{errors:?}"
    );
}

#[test]
fn cylinders_take_caps_per_vertex_too() {
    let mut h = Host::new();
    let g = h.d.new_object(DataType::GEOMETRY, "cylinder");
    vec3_array(
        &mut h,
        "vertex.position",
        g,
        &[[0.0, 0.0, 0.5], [0.0, 0.0, -0.5]],
    );
    h.set(g, "radius", DataType::FLOAT32, bytes(&[0.4f32]));
    u8_array(&mut h, "vertex.cap", g, &[0, 1]);
    h.d.commit(Subject::Object(g));
    // Open towards the eye: it sees the far disc through the tube.
    let d = centre_depth(&mut h, g);
    assert!((d - 3.5).abs() < 0.01, "{d}");
    u8_array(&mut h, "vertex.cap", g, &[1, 0]);
    h.d.commit(Subject::Object(g));
    let d = centre_depth(&mut h, g);
    assert!((d - 2.5).abs() < 0.01, "{d}");
    assert!(h.errors().is_empty(), "{:?}", h.errors());
}

#[test]
fn curves_join_their_segments_and_report_a_segment_past_the_end() {
    let mut h = Host::new();
    let g = h.d.new_object(DataType::GEOMETRY, "curve");
    // A polyline across the view; no index: every vertex but the last
    // starts a segment. The middle vertex's radius is the one seen.
    vec3_array(
        &mut h,
        "vertex.position",
        g,
        &[[-2.0, 0.0, 0.0], [0.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
    );
    f32_array(&mut h, "vertex.radius", g, &[0.1, 0.4, 0.1]);
    h.d.commit(Subject::Object(g));
    // The pixel is a little off the axis, where the sphere curves away.
    let d = centre_depth(&mut h, g);
    assert!((d - 2.6).abs() < 0.02, "{d}");
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    // A global radius where none is given per vertex.
    let g2 = h.d.new_object(DataType::GEOMETRY, "curve");
    vec3_array(
        &mut h,
        "vertex.position",
        g2,
        &[[-2.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
    );
    h.set(g2, "radius", DataType::FLOAT32, bytes(&[0.25f32]));
    h.d.commit(Subject::Object(g2));
    let d = centre_depth(&mut h, g2);
    assert!((d - 2.75).abs() < 0.02, "{d}");
    let index = h.array(
        DataType::ARRAY1D,
        DataType::UINT32,
        [2, 1, 1],
        &bytes(&[0u32, 1]),
    );
    h.set_object(g2, "primitive.index", DataType::ARRAY1D, index);
    h.d.release(index);
    h.d.commit(Subject::Object(g2));
    let errors = h.errors();
    assert!(
        errors
            .iter()
            .any(|(code, m)| *code == StatusCode::InvalidArgument
                && m.contains("curve segment 1 refers to vertex 2; there are 2 vertices")),
        "{errors:?}"
    );
}

#[test]
fn the_gpu_backend_draws_surfaces_in_a_volume_as_the_cpu_does() {
    let draw = |backend: &str| {
        let mut h = Host::on_backend(backend, std::sync::Arc::new(|_| {}));
        let field = h.field(|x| 0.3 + 0.1 * x as f32, None);
        let volume = h.volume(field);
        let g = sphere(&mut h);
        let m = matte(
            &mut h,
            Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[0.2f32, 0.6, 1.0])),
        );
        let s = surface(&mut h, g, m);
        let f = frame(&mut h, &[s], Some(volume));
        let p = h.pixels(f);
        let depth = h.depth_sized(f, SIZE, SIZE);
        assert!(h.errors().is_empty(), "{backend}: {:?}", h.errors());
        (p, depth)
    };
    let (gpu, gpu_depth) = draw("gpu");
    let (cpu, cpu_depth) = draw("cpu");
    let worst = gpu
        .iter()
        .zip(&cpu)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(worst <= 2, "colors differ by up to {worst}");
    for (g, c) in gpu_depth.iter().zip(&cpu_depth) {
        assert!(g == c || (g - c).abs() < 1e-4 * c.abs(), "depth {g} vs {c}");
    }
}

/// A square x, y in [-2, 2] at z = 0 whose vertex.attribute0 is
/// (x + 2) / 4: a scalar from 0 at the left edge to 1 at the right.
fn scalar_square(h: &mut Host) -> u64 {
    let g = h.d.new_object(DataType::GEOMETRY, "quad");
    vec3_array(
        h,
        "vertex.position",
        g,
        &[
            [-2.0, -2.0, 0.0],
            [2.0, -2.0, 0.0],
            [2.0, 2.0, 0.0],
            [-2.0, 2.0, 0.0],
        ],
    );
    let scalars = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32,
        [4, 1, 1],
        &bytes(&[0.0f32, 1.0, 1.0, 0.0]),
    );
    h.set_object(g, "vertex.attribute0", DataType::ARRAY1D, scalars);
    h.d.release(scalars);
    h.d.commit(Subject::Object(g));
    g
}

#[test]
fn a_color_map_sampler_colors_scalars_as_vtk_sends_them_on_either_backend() {
    for backend in ["cpu", "gpu"] {
        let mut h = Host::on_backend(backend, std::sync::Arc::new(|_| {}));
        let g = scalar_square(&mut h);
        // Blue to red, nearest: the left half blue, the right half red.
        let sampler = h.d.new_object(DataType::SAMPLER, "image1D");
        let map = h.array(
            DataType::ARRAY1D,
            DataType::FLOAT32_VEC3,
            [2, 1, 1],
            &bytes(&[0.0f32, 0.0, 1.0, 1.0, 0.0, 0.0]),
        );
        h.set_object(sampler, "image", DataType::ARRAY1D, map);
        h.d.set_param(
            Subject::Object(sampler),
            "filter",
            Input::String("nearest".into()),
        );
        h.d.commit(Subject::Object(sampler));
        let m = matte(&mut h, Input::Object(DataType::SAMPLER, sampler));
        let s = surface(&mut h, g, m);
        let f = frame(&mut h, &[s], None);
        let p = h.pixels(f);
        assert!(h.errors().is_empty(), "{backend}: {:?}", h.errors());
        let (left, right) = (
            pixel(&p, SIZE / 4, SIZE / 2),
            pixel(&p, 3 * SIZE / 4, SIZE / 2),
        );
        assert!(left[2] > 200 && left[0] == 0, "{backend}: {left:?}");
        assert!(right[0] > 200 && right[2] == 0, "{backend}: {right:?}");
        // The sampler committed again (linear now) shows in the next frame:
        // the middle is half of each.
        h.d.set_param(
            Subject::Object(sampler),
            "filter",
            Input::String("linear".into()),
        );
        h.d.commit(Subject::Object(sampler));
        let p = h.pixels(f);
        let middle = pixel(&p, SIZE / 2, SIZE / 2);
        assert!(
            middle[0].abs_diff(middle[2]) < 30 && middle[0] > 80,
            "{backend}: {middle:?}"
        );
        // Without its image the sampler fails its commit, and the frame
        // says which sampler its material could not use.
        let broken = h.d.new_object(DataType::SAMPLER, "image1D");
        h.d.commit(Subject::Object(broken));
        let said: Vec<String> = h.errors().into_iter().map(|(_, m)| m).collect();
        assert!(
            said.iter()
                .any(|m| m.contains("'image'") && m.contains("required")),
            "{said:?}"
        );
        let m2 = matte(&mut h, Input::Object(DataType::SAMPLER, broken));
        let s2 = surface(&mut h, g, m2);
        let f2 = frame(&mut h, &[s2], None);
        h.d.render_frame(f2, None);
        h.d.frame_ready(f2);
        let said: Vec<String> = h.errors().into_iter().map(|(_, m)| m).collect();
        assert!(
            said.iter()
                .any(|m| m.contains("colors by sampler 'image1D'")),
            "{backend}: {said:?}"
        );
        for o in [g, sampler, map, m, s, f, broken, m2, s2, f2] {
            h.d.release(o);
        }
    }
}

#[test]
fn primitive_and_transform_samplers_and_unknown_names() {
    let mut h = Host::new();
    let g = scalar_square(&mut h);
    // One value per quad: the quad's two triangles both read entry 1.
    let sampler = h.d.new_object(DataType::SAMPLER, "primitive");
    let values = h.array(
        DataType::ARRAY1D,
        DataType::UFIXED8_VEC4,
        [2, 1, 1],
        &[255u8, 0, 0, 255, 0, 255, 0, 255],
    );
    h.set_object(sampler, "array", DataType::ARRAY1D, values);
    h.set(sampler, "inOffset", DataType::UINT64, bytes(&[1u64]));
    h.d.commit(Subject::Object(sampler));
    let m = matte(&mut h, Input::Object(DataType::SAMPLER, sampler));
    let s = surface(&mut h, g, m);
    let f = frame(&mut h, &[s], None);
    let p = h.pixels(f);
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    for x in [2, SIZE / 2, SIZE - 3] {
        let c = pixel(&p, x, SIZE / 2);
        assert!(c[1] > 200 && c[0] == 0, "{c:?}");
    }
    // The scalar into green through a transform: dark at the left, green
    // at the right; an unknown attribute name is warned about.
    let t = h.d.new_object(DataType::SAMPLER, "transform");
    let to_green: [f32; 16] = [
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ];
    h.set(t, "outTransform", DataType::FLOAT32_MAT4, bytes(&to_green));
    h.d.commit(Subject::Object(t));
    let m2 = matte(&mut h, Input::Object(DataType::SAMPLER, t));
    let s2 = surface(&mut h, g, m2);
    let f2 = frame(&mut h, &[s2], None);
    let p = h.pixels(f2);
    let (left, right) = (pixel(&p, 1, SIZE / 2), pixel(&p, SIZE - 2, SIZE / 2));
    assert!(
        left[1] < 40 && right[1] > 150 && left[0] == 0,
        "{left:?} {right:?}"
    );
    h.d.set_param(
        Subject::Object(t),
        "inAttribute",
        Input::String("worldPosition".into()),
    );
    h.d.commit(Subject::Object(t));
    let warnings = h.messages(Severity::Warning);
    assert!(
        warnings
            .iter()
            .any(|m| m.contains("inAttribute 'worldPosition'")),
        "{warnings:?}"
    );
    for o in [g, sampler, values, m, s, f, t, m2, s2, f2] {
        h.d.release(o);
    }
}

#[test]
fn alpha_modes_blend_mask_and_warn() {
    let mut h = Host::new();
    let g = sphere(&mut h);
    let draw = |h: &mut Host, params: Vec<(&str, Input)>| {
        let m = h.d.new_object(DataType::MATERIAL, "matte");
        h.d.set_param(
            Subject::Object(m),
            "color",
            Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[1.0f32, 1.0, 0.0])),
        );
        for (name, value) in params {
            h.d.set_param(Subject::Object(m), name, value);
        }
        h.d.commit(Subject::Object(m));
        let s = surface(h, g, m);
        let f = frame(h, &[s], None);
        let p = h.pixels(f);
        for o in [m, s, f] {
            h.d.release(o);
        }
        (pixel(&p, SIZE / 2, SIZE / 2), pixel(&p, 0, 0))
    };
    let half = || Input::Bytes(DataType::FLOAT32, bytes(&[0.5f32]));
    let opaque = draw(&mut h, vec![]);
    let blended = draw(
        &mut h,
        vec![
            ("opacity", half()),
            ("alphaMode", Input::String("blend".into())),
        ],
    );
    let masked = draw(
        &mut h,
        vec![
            ("opacity", half()),
            ("alphaMode", Input::String("mask".into())),
            (
                "alphaCutoff",
                Input::Bytes(DataType::FLOAT32, bytes(&[0.6f32])),
            ),
        ],
    );
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    // Blended: between the opaque sphere and the background; masked out
    // below its cutoff: the background.
    let (opaque, background) = opaque;
    let (blended, masked) = (blended.0, masked.0);
    assert!(
        blended[0] < opaque[0] - 40 && blended[0] > background[0] + 40,
        "{blended:?} {opaque:?} {background:?}"
    );
    assert_eq!(masked, background);
    // Opacity under alphaMode opaque, and an unknown mode, are warned about.
    draw(&mut h, vec![("opacity", half())]);
    draw(&mut h, vec![("alphaMode", Input::String("dither".into()))]);
    let warnings = h.messages(Severity::Warning);
    assert!(
        warnings
            .iter()
            .any(|m| m.contains("under alphaMode opaque is drawn opaque")),
        "{warnings:?}"
    );
    assert!(
        warnings.iter().any(|m| m.contains("alphaMode 'dither'")),
        "{warnings:?}"
    );
}

#[test]
fn opacity_from_an_attribute_or_a_sampler_cuts_a_surface_on_either_backend() {
    for backend in ["cpu", "gpu"] {
        let mut h = Host::on_backend(backend, std::sync::Arc::new(|_| {}));
        // attribute0 runs from 0 at the square's left edge to 1 at its
        // right; the square fills the view.
        let g = scalar_square(&mut h);
        let red = || Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[1.0f32, 0.0, 0.0]));
        let draw = |h: &mut Host, params: Vec<(&str, Input)>| {
            let m = h.d.new_object(DataType::MATERIAL, "matte");
            h.d.set_param(Subject::Object(m), "color", red());
            for (name, value) in params {
                h.d.set_param(Subject::Object(m), name, value);
            }
            h.d.commit(Subject::Object(m));
            let s = surface(h, g, m);
            let f = frame(h, &[s], None);
            let p = h.pixels(f);
            for o in [m, s, f] {
                h.d.release(o);
            }
            [SIZE / 8, 3 * SIZE / 8, 5 * SIZE / 8, 7 * SIZE / 8].map(|x| pixel(&p, x, SIZE / 2))
        };
        let background = draw(
            &mut h,
            vec![
                ("opacity", Input::Bytes(DataType::FLOAT32, bytes(&[0.0f32]))),
                ("alphaMode", Input::String("blend".into())),
            ],
        )[0];
        let masked = draw(
            &mut h,
            vec![
                ("opacity", Input::String("attribute0".into())),
                ("alphaMode", Input::String("mask".into())),
            ],
        );
        // The sampler's image: 0 then 1, nearest, read at attribute0.
        let sampler = h.d.new_object(DataType::SAMPLER, "image1D");
        let steps = h.array(
            DataType::ARRAY1D,
            DataType::FLOAT32,
            [2, 1, 1],
            &bytes(&[0.0f32, 1.0]),
        );
        h.set_object(sampler, "image", DataType::ARRAY1D, steps);
        h.d.set_param(
            Subject::Object(sampler),
            "inAttribute",
            Input::String("attribute0".into()),
        );
        h.d.set_param(
            Subject::Object(sampler),
            "filter",
            Input::String("nearest".into()),
        );
        h.d.commit(Subject::Object(sampler));
        let sampled = draw(
            &mut h,
            vec![
                ("opacity", Input::Object(DataType::SAMPLER, sampler)),
                ("alphaMode", Input::String("blend".into())),
            ],
        );
        // Blended by attribute0: redder to the right.
        let blended = draw(
            &mut h,
            vec![
                ("opacity", Input::String("attribute0".into())),
                ("alphaMode", Input::String("blend".into())),
            ],
        );
        assert!(h.errors().is_empty(), "{backend}: {:?}", h.errors());
        for cut in [masked, sampled] {
            assert_eq!(&cut[..2], &[background; 2], "{backend}: {cut:?}");
            for c in &cut[2..] {
                assert!(c[0] > 200 && c[1] == 0 && c[2] == 0, "{backend}: {cut:?}");
            }
        }
        let reds = blended.map(|c| c[0]);
        assert!(
            reds.windows(2).all(|w| w[1] > w[0] + 20),
            "{backend}: {blended:?}"
        );
        // An opacity from an attribute under alphaMode opaque, and one
        // naming no attribute, are warned about.
        draw(
            &mut h,
            vec![("opacity", Input::String("attribute0".into()))],
        );
        draw(
            &mut h,
            vec![("opacity", Input::String("temperature".into()))],
        );
        let warnings = h.messages(Severity::Warning);
        assert!(
            warnings
                .iter()
                .any(|m| m
                    .contains("opacity from attribute0 under alphaMode opaque is drawn opaque")),
            "{warnings:?}"
        );
        assert!(
            warnings
                .iter()
                .any(|m| m.contains("opacity names 'temperature'")),
            "{warnings:?}"
        );
        for o in [g, sampler, steps] {
            h.d.release(o);
        }
    }
}

#[test]
fn point_and_spot_lights_light_surfaces_through_the_world() {
    for backend in ["cpu", "gpu"] {
        let mut h = Host::on_backend(backend, std::sync::Arc::new(|_| {}));
        let g = scalar_square(&mut h);
        let m = matte(
            &mut h,
            Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[1.0f32, 1.0, 1.0])),
        );
        let s = surface(&mut h, g, m);
        // A point light 1 in front of the square's centre: bright there,
        // dimmer towards the edges.
        let point = h.d.new_object(DataType::LIGHT, "point");
        h.set(
            point,
            "position",
            DataType::FLOAT32_VEC3,
            bytes(&[0.0f32, 0.0, 1.0]),
        );
        h.set(point, "intensity", DataType::FLOAT32, bytes(&[0.8f32]));
        h.d.commit(Subject::Object(point));
        let f = lit_frame(&mut h, &[s], None, &[point]);
        let p = h.pixels(f);
        assert!(h.errors().is_empty(), "{backend}: {:?}", h.errors());
        let (centre, edge) = (pixel(&p, SIZE / 2, SIZE / 2), pixel(&p, 1, SIZE / 2));
        assert!(
            centre[0] > 150 && edge[0] + 60 < centre[0],
            "{backend}: {centre:?} {edge:?}"
        );
        // A narrow spot aimed at the centre leaves the edge dark.
        let spot = h.d.new_object(DataType::LIGHT, "spot");
        h.set(
            spot,
            "position",
            DataType::FLOAT32_VEC3,
            bytes(&[0.0f32, 0.0, 1.0]),
        );
        h.set(spot, "openingAngle", DataType::FLOAT32, bytes(&[0.6f32]));
        h.d.commit(Subject::Object(spot));
        let f2 = lit_frame(&mut h, &[s], None, &[spot]);
        let p = h.pixels(f2);
        let (centre, edge) = (pixel(&p, SIZE / 2, SIZE / 2), pixel(&p, 1, SIZE / 2));
        assert!(
            centre[0] > 150 && edge[0] == 0,
            "{backend}: {centre:?} {edge:?}"
        );
        // The default renderer shades as the reference device does, in
        // an eye light that leaves no part of the square dark.
        let f3 = frame_of(&mut h, "default", &[s], None, &[spot]);
        let p = h.pixels(f3);
        let (centre, edge) = (pixel(&p, SIZE / 2, SIZE / 2), pixel(&p, 1, SIZE / 2));
        assert!(
            centre[0] == 255 && edge[0] > 200,
            "{backend}: {centre:?} {edge:?}"
        );
        // A bad direction fails the spot's commit.
        h.set(
            spot,
            "direction",
            DataType::FLOAT32_VEC3,
            bytes(&[0.0f32, 0.0, 0.0]),
        );
        h.d.commit(Subject::Object(spot));
        let said: Vec<String> = h.errors().into_iter().map(|(_, m)| m).collect();
        assert!(
            said.iter().any(|m| m.contains("has no direction")),
            "{said:?}"
        );
        for o in [g, m, s, point, f, spot, f2, f3] {
            h.d.release(o);
        }
    }
}

#[test]
fn physically_based_shows_its_base_color_and_emission_and_takes_its_whole_table() {
    let mut h = Host::new();
    let g = sphere(&mut h);
    let m = h.d.new_object(DataType::MATERIAL, "physicallyBased");
    h.set(
        m,
        "baseColor",
        DataType::FLOAT32_VEC3,
        bytes(&[0.5f32, 0.0, 0.0]),
    );
    h.set(
        m,
        "emissive",
        DataType::FLOAT32_VEC3,
        bytes(&[0.0f32, 0.0, 1.0]),
    );
    h.set(m, "metallic", DataType::FLOAT32, bytes(&[0.2f32]));
    // glTF's layers beyond metallic-roughness are accepted quietly.
    h.set(m, "clearcoat", DataType::FLOAT32, bytes(&[0.5f32]));
    h.set(m, "ior", DataType::FLOAT32, bytes(&[1.4f32]));
    h.d.commit(Subject::Object(m));
    let s = surface(&mut h, g, m);
    let f = frame(&mut h, &[s], None);
    let p = h.pixels(f);
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    assert!(
        h.messages(Severity::Warning).is_empty(),
        "{:?}",
        h.messages(Severity::Warning)
    );
    // Head-on in the eye light: the base color plus the blue it emits.
    let c = pixel(&p, SIZE / 2, SIZE / 2);
    assert!(
        (c[0] as i32 - 127).abs() <= 3 && c[1] == 0 && c[2] == 255,
        "{c:?}"
    );
    // A metallic from a sampler is not modelled, and the host hears so.
    h.d.set_param(
        Subject::Object(m),
        "metallic",
        Input::String("attribute0".into()),
    );
    h.d.commit(Subject::Object(m));
    let warnings = h.messages(Severity::Warning);
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("metallic from a sampler or an attribute is not modelled")),
        "{warnings:?}"
    );
}

#[test]
fn a_material_never_committed_draws_with_its_defaults() {
    let mut h = Host::new();
    let g = sphere(&mut h);
    let m = h.d.new_object(DataType::MATERIAL, "matte");
    // Set and never committed: it does not take effect.
    h.set(
        m,
        "color",
        DataType::FLOAT32_VEC3,
        bytes(&[1.0f32, 0.0, 0.0]),
    );
    let s = surface(&mut h, g, m);
    let f = frame(&mut h, &[s], None);
    let p = h.pixels(f);
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    // The default 0.8 grey, head-on.
    let c = pixel(&p, SIZE / 2, SIZE / 2);
    assert!(
        c[0] == c[1] && c[1] == c[2] && (c[0] as i32 - 204).abs() <= 3,
        "{c:?}"
    );
}

#[test]
fn instances_color_one_mesh_by_their_uniform_attributes_on_either_backend() {
    for backend in ["cpu", "gpu"] {
        let mut h = Host::on_backend(backend, std::sync::Arc::new(|_| {}));
        // One green sphere colored by its `color` attribute...
        let g = sphere(&mut h);
        let green = h.array(
            DataType::ARRAY1D,
            DataType::FLOAT32_VEC4,
            [1, 1, 1],
            &bytes(&[0.0f32, 1.0, 0.0, 1.0]),
        );
        h.set_object(g, "vertex.color", DataType::ARRAY1D, green);
        h.d.release(green);
        h.d.commit(Subject::Object(g));
        let m = matte(&mut h, Input::String("color".into()));
        let s = surface(&mut h, g, m);
        let group = h.d.new_object(DataType::GROUP, "");
        h.set_objects(group, "surface", DataType::SURFACE, &[s]);
        h.d.commit(Subject::Object(group));
        // ...placed twice, left in red and right with no color of its own.
        let mut instances = Vec::new();
        for (x, color) in [(-0.6f32, Some([1.0f32, 0.0, 0.0, 1.0])), (0.6, None)] {
            let i = h.d.new_object(DataType::INSTANCE, "transform");
            h.set_object(i, "group", DataType::GROUP, group);
            let m = glam::Mat4::from_translation(glam::Vec3::new(x, 0.0, 0.0)).to_cols_array();
            h.set(i, "transform", DataType::FLOAT32_MAT4, bytes(&m));
            if let Some(c) = color {
                h.set(i, "color", DataType::FLOAT32_VEC4, bytes(&c));
            }
            h.d.commit(Subject::Object(i));
            instances.push(i);
        }
        let world = h.d.new_object(DataType::WORLD, "");
        h.set_objects(world, "instance", DataType::INSTANCE, &instances);
        h.d.commit(Subject::Object(world));
        let f = frame_for(&mut h, "default", world);
        let p = h.pixels(f);
        assert!(h.errors().is_empty(), "{backend}: {:?}", h.errors());
        // The sphere's centres at x = -+0.6 from 3 away, 60 degrees: a
        // fifth of the half-width either side of the middle.
        let (left, right) = (SIZE / 2 - SIZE * 17 / 100, SIZE / 2 + SIZE * 17 / 100);
        let (l, r) = (pixel(&p, left, SIZE / 2), pixel(&p, right, SIZE / 2));
        assert!(l[0] > 200 && l[1] == 0, "{backend}: left {l:?}");
        assert!(r[1] > 200 && r[0] == 0, "{backend}: right {r:?}");
    }
}

#[test]
fn an_opacity_outside_zero_to_one_is_clamped_with_a_warning() {
    let mut h = Host::new();
    let m = h.d.new_object(DataType::MATERIAL, "matte");
    h.set(m, "opacity", DataType::FLOAT32, bytes(&[1.5f32]));
    h.d.set_param(
        Subject::Object(m),
        "alphaMode",
        Input::String("blend".into()),
    );
    h.d.commit(Subject::Object(m));
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    let warnings = h.messages(Severity::Warning);
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("opacity 1.5 lies outside [0, 1]; clamped")),
        "{warnings:?}"
    );
}

/// Sets frame channel `name` to ANARI type `ty`.
fn channel(h: &mut Host, frame: u64, name: &str, ty: DataType) {
    h.set(frame, name, DataType::DATA_TYPE, bytes(&[ty as i32]));
    h.d.commit(Subject::Object(frame));
}

/// Mapped channel `name` of rendered `frame`: its type and its bytes.
fn mapped(h: &mut Host, frame: u64, name: &str, bytes_per_pixel: usize) -> (DataType, Vec<u8>) {
    let m = h.d.map_frame(frame, name).expect("the channel maps");
    assert_eq!(m.size, glam::UVec2::splat(SIZE));
    // SAFETY: a mapped channel of SIZE^2 pixels, valid until unmap.
    let b = unsafe { std::slice::from_raw_parts(m.ptr, bytes_per_pixel * (SIZE * SIZE) as usize) }
        .to_vec();
    h.d.unmap_frame(frame, name);
    (m.ty, b)
}

fn u32_at(b: &[u8], x: u32, y: u32) -> u32 {
    let i = 4 * (y * SIZE + x) as usize;
    u32::from_ne_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

#[test]
fn id_normal_and_albedo_channels_name_what_each_pixel_shows_on_either_backend() {
    for backend in ["cpu", "gpu"] {
        let mut h = Host::on_backend(backend, std::sync::Arc::new(|_| {}));
        // A red sphere of id 11 placed by instance 21 on the left; on the
        // right the same sphere in the world directly, with no id.
        let g = sphere(&mut h);
        let red = Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[1.0f32, 0.0, 0.0]));
        let m = matte(&mut h, red);
        let s = surface(&mut h, g, m);
        h.set(s, "id", DataType::UINT32, bytes(&[11u32]));
        h.d.commit(Subject::Object(s));
        let group = h.d.new_object(DataType::GROUP, "");
        h.set_objects(group, "surface", DataType::SURFACE, &[s]);
        h.d.commit(Subject::Object(group));
        let i = h.d.new_object(DataType::INSTANCE, "transform");
        h.set_object(i, "group", DataType::GROUP, group);
        let left = glam::Mat4::from_translation(glam::Vec3::new(-0.6, 0.0, 0.0)).to_cols_array();
        h.set(i, "transform", DataType::FLOAT32_MAT4, bytes(&left));
        h.set(i, "id", DataType::UINT32, bytes(&[21u32]));
        h.d.commit(Subject::Object(i));
        let g2 = sphere(&mut h);
        let right = h.array(
            DataType::ARRAY1D,
            DataType::FLOAT32_VEC3,
            [1, 1, 1],
            &bytes(&[0.6f32, 0.0, 0.0]),
        );
        h.set_object(g2, "vertex.position", DataType::ARRAY1D, right);
        h.d.release(right);
        h.d.commit(Subject::Object(g2));
        let s2 = surface(&mut h, g2, m);
        let world = h.d.new_object(DataType::WORLD, "");
        h.set_objects(world, "instance", DataType::INSTANCE, &[i]);
        h.set_objects(world, "surface", DataType::SURFACE, &[s2]);
        h.d.commit(Subject::Object(world));
        let f = frame_for(&mut h, "default", world);
        channel(&mut h, f, "channel.objectId", DataType::UINT32);
        channel(&mut h, f, "channel.instanceId", DataType::UINT32);
        channel(&mut h, f, "channel.primitiveId", DataType::UINT32);
        channel(&mut h, f, "channel.normal", DataType::FIXED16_VEC3);
        channel(&mut h, f, "channel.albedo", DataType::UFIXED8_RGB_SRGB);
        h.pixels(f);
        assert!(h.errors().is_empty(), "{backend}: {:?}", h.errors());
        let (l, r, y) = (
            SIZE / 2 - SIZE * 17 / 100,
            SIZE / 2 + SIZE * 17 / 100,
            SIZE / 2,
        );
        let (ty, objects) = mapped(&mut h, f, "channel.objectId", 4);
        assert_eq!(ty, DataType::UINT32);
        let none = u32::MAX;
        assert_eq!(
            [
                u32_at(&objects, l, y),
                u32_at(&objects, r, y),
                u32_at(&objects, 0, 0)
            ],
            [11, none, none],
            "{backend}"
        );
        let (_, instances) = mapped(&mut h, f, "channel.instanceId", 4);
        assert_eq!(
            [u32_at(&instances, l, y), u32_at(&instances, r, y)],
            [21, none],
            "{backend}"
        );
        let (_, primitives) = mapped(&mut h, f, "channel.primitiveId", 4);
        assert_eq!(
            [u32_at(&primitives, l, y), u32_at(&primitives, 0, 0)],
            [0, none],
            "{backend}"
        );
        // At the sphere's centre the normal faces the camera (+z).
        let (ty, normals) = mapped(&mut h, f, "channel.normal", 6);
        assert_eq!(ty, DataType::FIXED16_VEC3);
        let at = 6 * (y * SIZE + l) as usize;
        let z = i16::from_ne_bytes([normals[at + 4], normals[at + 5]]);
        assert!(z > 29_500, "{backend}: normal z {z}");
        let (ty, albedo) = mapped(&mut h, f, "channel.albedo", 3);
        assert_eq!(ty, DataType::UFIXED8_RGB_SRGB);
        let at = 3 * (y * SIZE + r) as usize;
        assert_eq!(&albedo[at..at + 3], &[255, 0, 0], "{backend}");
        assert_eq!(&albedo[0..3], &[0, 0, 0], "{backend}: the background");
    }
}

#[test]
fn hit_channels_refuse_other_types_and_unset_channels_by_name() {
    let mut h = Host::new();
    let g = sphere(&mut h);
    let m = matte(
        &mut h,
        Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[1.0f32, 1.0, 1.0])),
    );
    let s = surface(&mut h, g, m);
    let f = frame(&mut h, &[s], None);
    channel(&mut h, f, "channel.normal", DataType::UINT32);
    let errors = h.errors();
    assert!(
        errors
            .iter()
            .any(|(code, e)| *code == StatusCode::InvalidArgument
                && e.contains(
                    "channel.normal ANARI_UINT32 is not ANARI_FLOAT32_VEC3 or ANARI_FIXED16_VEC3"
                )),
        "{errors:?}"
    );
    channel(&mut h, f, "channel.normal", DataType::FLOAT32_VEC3);
    h.pixels(f);
    assert!(h.errors().is_empty());
    assert!(h.d.map_frame(f, "channel.albedo").is_none());
    let errors = h.errors();
    assert!(
        errors
            .iter()
            .any(|(code, e)| *code == StatusCode::InvalidOperation
                && e.contains("the frame has no channel.albedo channel; set 'channel.albedo'")),
        "{errors:?}"
    );
    let (ty, _) = mapped(&mut h, f, "channel.normal", 12);
    assert_eq!(ty, DataType::FLOAT32_VEC3);
}

#[test]
fn accumulation_antialiases_an_edge_through_pixel_centres_over_64_samples() {
    for backend in ["cpu", "gpu"] {
        let mut h = Host::on_backend(backend, std::sync::Arc::new(|_| {}));
        // A red square whose right edge runs just right of the centres of
        // column 12 (an orthographic window 2 wide over SIZE = 24 pixels).
        let edge = 1.0 / 24.0 + 0.002;
        let g = h.d.new_object(DataType::GEOMETRY, "triangle");
        vec3_array(
            &mut h,
            "vertex.position",
            g,
            &[
                [-2.0, -2.0, 0.0],
                [edge, -2.0, 0.0],
                [edge, 2.0, 0.0],
                [-2.0, -2.0, 0.0],
                [edge, 2.0, 0.0],
                [-2.0, 2.0, 0.0],
            ],
        );
        h.d.commit(Subject::Object(g));
        let red = Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[1.0f32, 0.0, 0.0]));
        let m = matte(&mut h, red);
        let s = surface(&mut h, g, m);
        let f = frame(&mut h, &[s], None);
        let camera = h.d.new_object(DataType::CAMERA, "orthographic");
        h.set(
            camera,
            "position",
            DataType::FLOAT32_VEC3,
            bytes(&[0.0f32, 0.0, 3.0]),
        );
        h.set(camera, "height", DataType::FLOAT32, bytes(&[2.0f32]));
        h.d.commit(Subject::Object(camera));
        h.set_object(f, "camera", DataType::CAMERA, camera);
        h.set(f, "accumulation", DataType::BOOL, vec![1]);
        h.d.commit(Subject::Object(f));
        let samples = |h: &mut Host| match h.d.property(Subject::Object(f), "numSamples", true) {
            Some(anari_library_caveray::device::Property::Int32(n)) => n,
            other => panic!("numSamples {other:?}"),
        };
        let y = SIZE / 2;
        let first = h.pixels(f);
        // The first sample is each pixel's centre.
        let reds = |p: &[u8]| [11, 12, 13].map(|x| pixel(p, x, y)[0]);
        assert_eq!(reds(&first), [255, 255, 0], "{backend}");
        let mut last = first.clone();
        for _ in 1..64 {
            last = h.pixels(f);
        }
        assert_eq!(samples(&mut h), 64, "{backend}");
        let [inside, edge_pixel, outside] = reds(&last);
        assert_eq!((inside, outside), (255, 0), "{backend}");
        assert!(
            (112..=144).contains(&edge_pixel),
            "{backend}: the edge pixel after 64 samples: {edge_pixel}"
        );
        // Depth stays the pixel centre's: the square, 3 away.
        let depth = h.depth_sized(f, SIZE, SIZE);
        assert!(
            (depth[(y * SIZE + 12) as usize] - 3.0).abs() < 1e-4,
            "{backend}"
        );
        // Past 64 samples the image stands.
        same(&h.pixels(f), &last).unwrap();
        assert_eq!(samples(&mut h), 65, "{backend}");
        // Without accumulation an unchanged frame keeps its first image.
        h.set(f, "accumulation", DataType::BOOL, vec![0]);
        h.d.commit(Subject::Object(f));
        same(&h.pixels(f), &first).unwrap();
        same(&h.pixels(f), &first).unwrap();
        assert_eq!(samples(&mut h), 2, "{backend}");
        assert!(h.errors().is_empty(), "{backend}: {:?}", h.errors());
    }
}

#[test]
fn a_stereo_camera_reprojects_a_sphere_inside_a_volume_in_one_pass() {
    use anari_library_caveray::device::Status;
    use anari_library_caveray::render::{dssim, ColorData, Frame};
    use std::sync::{Arc, Mutex};
    let heard: Arc<Mutex<Vec<String>>> = Arc::default();
    let log = Arc::clone(&heard);
    let mut h = Host::on_backend(
        "gpu",
        Arc::new(move |s: Status| {
            if s.severity == Severity::Info {
                log.lock().unwrap().push(s.message);
            }
        }),
    );
    let field = h.field(|i| 0.2 + 0.1 * (i % 4) as f32, None);
    let volume = h.volume(field);
    let g = sphere(&mut h);
    let m = matte(
        &mut h,
        Input::Bytes(DataType::FLOAT32_VEC3, bytes(&[1.0f32, 0.8, 0.1])),
    );
    let s = surface(&mut h, g, m);
    let frame = frame(&mut h, &[s], Some(volume));
    let camera = h.d.new_object(DataType::CAMERA, "perspective");
    h.set(
        camera,
        "position",
        DataType::FLOAT32_VEC3,
        bytes(&[0.0f32, 0.0, 3.0]),
    );
    h.set(
        camera,
        "interpupillaryDistance",
        DataType::FLOAT32,
        bytes(&[0.3f32]),
    );
    h.set_object(frame, "camera", DataType::CAMERA, camera);
    let n = 2 * SIZE;
    let eye = |h: &mut Host, mode: &str, width: u32| {
        h.d.set_param(
            Subject::Object(camera),
            "stereoMode",
            Input::String(mode.into()),
        );
        h.d.commit(Subject::Object(camera));
        h.set(frame, "size", DataType::UINT32_VEC2, bytes(&[width, n]));
        h.d.commit(Subject::Object(frame));
        h.pixels_sized(frame, width, n)
    };
    let left = eye(&mut h, "left", n);
    let right = eye(&mut h, "right", n);
    heard.lock().unwrap().clear();
    let pair = eye(&mut h, "sideBySide", 2 * n);
    let said = heard.lock().unwrap().clone();
    assert!(
        said.iter()
            .any(|m| m.contains("stereo frame: both eyes in one re-projection pass")),
        "{said:?}"
    );
    let as_frame = |pixels: Vec<u8>| Frame {
        size: glam::UVec2::splat(n),
        color: ColorData::Rgba8(pixels),
        depth: None,
        hits: None,
        samples: 0,
    };
    let half = |x0: usize| -> Vec<u8> {
        (0..n as usize)
            .flat_map(|y| {
                let start = 4 * (y * 2 * n as usize + x0);
                pair[start..start + 4 * n as usize].to_vec()
            })
            .collect()
    };
    // The left eye is its own pass; the right eye's sphere is its own
    // rays', the volume around it re-projected.
    assert_eq!(half(0), left);
    let d = dssim(&as_frame(half(n as usize)), &as_frame(right.clone())).unwrap();
    let unmoved = dssim(&as_frame(left), &as_frame(right)).unwrap();
    eprintln!("sideBySide with a sphere: right DSSIM {d:.4}, left as right {unmoved:.4}");
    assert!(
        d < 0.01 && d < 0.5 * unmoved,
        "DSSIM {d} (left as right {unmoved})"
    );
    assert!(h.errors().is_empty(), "{:?}", h.errors());
    h.d.release(camera);
}
