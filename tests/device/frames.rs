//! Frames as hosts render them: OpenCOVER renders an unchanged channel up
//! to 64 times and VTK several times per frame; an unchanged frame keeps
//! its image (refines it, with `accumulation`: tests/device/surfaces.rs),
//! counts the renders in `numSamples`, and any change of its inputs
//! renders anew.

use crate::common;

use anari_library_caveray::device::{DataType, Property, Severity, Status, StatusCode, Subject};
use common::device::{bytes, same, Host};
use std::sync::Arc;

fn property(h: &mut Host, frame: u64, name: &str) -> Option<Property> {
    h.d.property(Subject::Object(frame), name, true)
}

/// A default renderer shading by `shading`, set on `frame` (not
/// committed).
fn shaded_renderer(h: &mut Host, frame: u64, shading: &str) -> u64 {
    let r = h.d.new_object(DataType::RENDERER, "default");
    h.d.set_param(
        Subject::Object(r),
        "shading",
        anari_library_caveray::device::Input::String(shading.into()),
    );
    h.d.commit(Subject::Object(r));
    h.set_object(frame, "renderer", DataType::RENDERER, r);
    r
}

#[test]
fn unchanged_frames_keep_their_image_and_changes_render_anew() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.3f32]));
    let (frame, camera) = h.frame(volume, 3.0);

    let first = h.pixels(frame);
    assert_eq!(
        property(&mut h, frame, "numSamples"),
        Some(Property::Int32(1))
    );
    for n in 2..=64 {
        let again = h.pixels(frame);
        same(&again, &first).unwrap();
        assert_eq!(
            property(&mut h, frame, "numSamples"),
            Some(Property::Int32(n))
        );
    }
    assert_eq!(
        property(&mut h, frame, "renderProgress"),
        Some(Property::Float32(1.0))
    );

    // Committing the renderer with the same values changes nothing.
    let renderer = h.d.new_object(DataType::RENDERER, "default");
    h.d.commit(Subject::Object(renderer));
    h.set_object(frame, "renderer", DataType::RENDERER, renderer);
    h.d.commit(Subject::Object(frame));
    same(&h.pixels(frame), &first).unwrap();
    assert_eq!(
        property(&mut h, frame, "numSamples"),
        Some(Property::Int32(65))
    );

    // A camera that moved: a new image.
    h.set(
        camera,
        "position",
        DataType::FLOAT32_VEC3,
        bytes(&[0.4f32, 0.0, 2.5]),
    );
    h.d.commit(Subject::Object(camera));
    let moved = h.pixels(frame);
    assert!(
        same(&moved, &first).is_err(),
        "the moved camera shows the old image"
    );
    assert_eq!(
        property(&mut h, frame, "numSamples"),
        Some(Property::Int32(1))
    );

    // A recommitted volume (new derived data, even if equal): rendered again.
    h.d.commit(Subject::Object(volume));
    same(&h.pixels(frame), &moved).unwrap();
    assert_eq!(
        property(&mut h, frame, "numSamples"),
        Some(Property::Int32(1))
    );

    // Another size: rendered again, at that size.
    h.set(frame, "size", DataType::UINT32_VEC2, bytes(&[8u32, 8]));
    h.d.commit(Subject::Object(frame));
    h.d.render_frame(frame, None);
    let mapped = h.d.map_frame(frame, "channel.color").unwrap();
    assert_eq!(mapped.size.to_array(), [8, 8]);
    h.d.unmap_frame(frame, "channel.color");
    assert_eq!(
        property(&mut h, frame, "numSamples"),
        Some(Property::Int32(1))
    );
    let problems: Vec<_> =
        h.d.take_statuses()
            .into_iter()
            .filter(|s| (s.severity as i32) <= Severity::Warning as i32)
            .map(|s| s.message)
            .collect();
    assert!(problems.is_empty(), "{problems:?}");
}

#[test]
fn a_failed_render_is_never_kept() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    let (frame, _camera) = h.frame(volume, 3.0);
    // Without a size the render fails, twice, and is not "unchanged".
    h.d.unset_param(Subject::Object(frame), "size");
    h.d.commit(Subject::Object(frame));
    for _ in 0..2 {
        h.d.render_frame(frame, None);
        assert!(h.d.map_frame(frame, "channel.color").is_none());
        assert_eq!(
            property(&mut h, frame, "numSamples"),
            Some(Property::Int32(0))
        );
    }
    let errors = h.messages(Severity::Error);
    assert!(
        errors
            .iter()
            .filter(|e| e.starts_with("anariRenderFrame") && e.contains("'size'"))
            .count()
            == 2,
        "{errors:?}"
    );
}

#[test]
fn orthographic_cameras_and_clip_ranges_through_the_device() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.3f32]));
    let (frame, _perspective) = h.frame(volume, 3.0);
    let perspective = h.pixels(frame);

    let ortho = h.d.new_object(DataType::CAMERA, "orthographic");
    h.set(
        ortho,
        "position",
        DataType::FLOAT32_VEC3,
        bytes(&[0.0f32, 0.0, 3.0]),
    );
    h.set(ortho, "height", DataType::FLOAT32, bytes(&[3.0f32]));
    h.d.commit(Subject::Object(ortho));
    h.set_object(frame, "camera", DataType::CAMERA, ortho);
    h.d.commit(Subject::Object(frame));
    let parallel = h.pixels(frame);
    let lit = parallel.chunks(4).filter(|p| p[0] > 10).count();
    assert!(lit > 100, "the orthographic view shows {lit} lit pixels");
    assert!(same(&parallel, &perspective).is_err());

    // Far before the volume: the background only.
    h.set(ortho, "far", DataType::FLOAT32, bytes(&[1.0f32]));
    h.d.commit(Subject::Object(ortho));
    let clipped = h.pixels(frame);
    assert!(
        clipped.chunks(4).all(|p| p[..3] == [0, 0, 0]),
        "far 1 still shows the volume"
    );

    // near >= far, or negative: refused at commit, with the reason.
    h.set(ortho, "near", DataType::FLOAT32, bytes(&[2.0f32]));
    h.d.commit(Subject::Object(ortho));
    let errors = h.messages(Severity::Error);
    assert!(
        errors
            .iter()
            .any(|e| e.contains("near 2 and far 1 must satisfy 0 <= near < far")),
        "{errors:?}"
    );
}

#[test]
fn renderer_clip_planes_and_sampling_rate_through_the_device() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.3f32]));
    let (frame, _camera) = h.frame(volume, 3.0);
    let with = |h: &mut Host, setup: &dyn Fn(&mut Host, u64)| {
        let r = h.d.new_object(DataType::RENDERER, "default");
        setup(h, r);
        h.d.commit(Subject::Object(r));
        h.set_object(frame, "renderer", DataType::RENDERER, r);
        h.d.commit(Subject::Object(frame));
        h.d.release(r);
        h.pixels(frame)
    };
    let rate4 = with(&mut h, &|h, r| {
        h.set(r, "volumeSamplingRate", DataType::FLOAT32, bytes(&[4.0f32]))
    });
    let half_step = with(&mut h, &|h, r| {
        h.set(r, "stepFactor", DataType::FLOAT32, bytes(&[0.5f32]))
    });
    same(&rate4, &half_step).unwrap();

    let clipped = with(&mut h, &|h, r| {
        let planes = h.array(
            DataType::ARRAY1D,
            DataType::FLOAT32_VEC4,
            [1, 1, 1],
            &bytes(&[1.0f32, 0.0, 0.0, 0.0]),
        );
        h.set_object(r, "clipPlane", DataType::ARRAY1D, planes);
        h.d.release(planes);
    });
    let size = common::device::SIZE as usize;
    let lit = |x: usize| (0..size).any(|y| clipped[4 * (y * size + x)] > 0);
    assert!(
        (0..size / 2 - 1).any(lit),
        "the kept half (x < 0) shows nothing"
    );
    assert!(
        !(size / 2 + 1..size).any(lit),
        "the clipped half (x > 0) shows the volume"
    );
    let errors = h.messages(Severity::Error);
    assert!(errors.is_empty(), "{errors:?}");
}

/// A frame of the ramp volume through a renderer `setup` prepares; the
/// errors its commit reported.
fn through_renderer(
    h: &mut Host,
    frame: u64,
    setup: &dyn Fn(&mut Host, u64),
) -> (Vec<u8>, Vec<(StatusCode, String)>) {
    let r = h.d.new_object(DataType::RENDERER, "default");
    setup(h, r);
    h.d.commit(Subject::Object(r));
    let errors = h.errors();
    h.set_object(frame, "renderer", DataType::RENDERER, r);
    h.d.commit(Subject::Object(frame));
    h.d.release(r);
    h.d.render_frame(frame, None);
    let pixels = match h.d.map_frame(frame, "channel.color") {
        Some(mapped) => {
            let n = (4 * mapped.size.x * mapped.size.y) as usize;
            // SAFETY: a mapped RGBA8 frame of its size, valid until unmap.
            let pixels = unsafe { std::slice::from_raw_parts(mapped.ptr, n) }.to_vec();
            h.d.unmap_frame(frame, "channel.color");
            pixels
        }
        None => Vec::new(),
    };
    h.errors();
    (pixels, errors)
}

fn clip_plane(plane: [f32; 4]) -> impl Fn(&mut Host, u64) {
    move |h: &mut Host, r: u64| {
        let a = h.array(
            DataType::ARRAY1D,
            DataType::FLOAT32_VEC4,
            [1, 1, 1],
            &bytes(&plane),
        );
        h.set_object(r, "clipPlane", DataType::ARRAY1D, a);
        h.d.release(a);
    }
}

#[test]
fn clip_plane_normals_of_any_finite_length_name_their_plane() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.3f32]));
    let (frame, _camera) = h.frame(volume, 3.0);
    let lit = |p: &[u8]| {
        p.chunks(4)
            .filter(|c| c[..3].iter().any(|&v| v > 0))
            .count()
    };
    let (all, _) = through_renderer(&mut h, frame, &|_, _| {});
    for (unit, scaled) in [
        ([1.0f32, 1.0, 1.0, 0.0], [3e38f32, 3e38, 3e38, 1.0]),
        ([1.0, 0.0, 0.0, 0.0], [1e-30, 0.0, 0.0, 0.0]),
        // Subnormal: 2^-130 and 2^-132, exactly.
        (
            [0.0, -1.0, 0.0, 0.25],
            [0.0, -f32::from_bits(1 << 19), 0.0, f32::from_bits(1 << 17)],
        ),
    ] {
        let (a, e) = through_renderer(&mut h, frame, &clip_plane(unit));
        assert!(e.is_empty(), "{unit:?}: {e:?}");
        let (b, e) = through_renderer(&mut h, frame, &clip_plane(scaled));
        assert!(e.is_empty(), "{scaled:?}: {e:?}");
        assert!(
            lit(&a) > 0 && lit(&a) < lit(&all),
            "{unit:?} cuts the volume"
        );
        assert_eq!(lit(&b), lit(&a), "{scaled:?} lights as {unit:?}");
        same(&b, &a).unwrap();
    }
    for bad in [
        [0.0f32, 0.0, 0.0, 1.0],
        [f32::INFINITY, 0.0, 0.0, 0.0],
        [1.0, f32::NAN, 0.0, 0.0],
        [1.0, 0.0, 0.0, f32::INFINITY],
    ] {
        let (_, e) = through_renderer(&mut h, frame, &clip_plane(bad));
        assert!(
            e.len() == 1
                && e[0].0 == StatusCode::InvalidArgument
                && e[0]
                    .1
                    .contains("needs a finite, non-zero normal and a finite distance"),
            "{bad:?}: {e:?}"
        );
    }
}

#[test]
fn background_images_are_held_to_the_background_colors_range() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    let (frame, _camera) = h.frame(volume, 3.0);
    let image = |pixels: [[f32; 4]; 4]| {
        move |h: &mut Host, r: u64| {
            let a = h.array(
                DataType::ARRAY2D,
                DataType::FLOAT32_VEC4,
                [2, 2, 1],
                &bytes(&pixels),
            );
            h.set_object(r, "background", DataType::ARRAY2D, a);
            h.d.release(a);
        }
    };
    let grey = [0.5f32, 0.5, 0.5, 1.0];
    let (good, e) = through_renderer(&mut h, frame, &image([grey; 4]));
    assert!(e.is_empty() && !good.is_empty(), "{e:?}");
    let hostile = [
        [f32::NAN, 0.0, 0.0, 1.0],
        [f32::INFINITY, 0.0, 0.0, 1.0],
        [-5.0, 0.0, 0.0, 1.0],
        grey,
    ];
    let (_, e) = through_renderer(&mut h, frame, &image(hostile));
    assert!(
        e.len() == 1
            && e[0].0 == StatusCode::InvalidArgument
            && e[0].1.contains("'background' pixel (0, 0) is [NaN, 0, 0, 1]; every pixel must be four numbers in [0, 1], as the background color's"),
        "{e:?}"
    );
    for (i, bad) in [
        [f32::INFINITY, 0.0, 0.0, 1.0],
        [-5.0, 0.0, 0.0, 1.0],
        [0.5, 0.5, 1.5, 1.0],
    ]
    .into_iter()
    .enumerate()
    {
        let mut pixels = [grey; 4];
        pixels[3] = bad;
        let (_, e) = through_renderer(&mut h, frame, &image(pixels));
        assert!(
            e.len() == 1 && e[0].1.contains("'background' pixel (1, 1) is"),
            "{i}: {e:?}"
        );
    }
    // The color is refused the same way.
    let (_, e) = through_renderer(&mut h, frame, &|h: &mut Host, r: u64| {
        h.set(
            r,
            "background",
            DataType::FLOAT32_VEC4,
            bytes(&[-5.0f32, 0.0, 0.0, 1.0]),
        );
    });
    assert!(
        e.len() == 1 && e[0].1.contains("background must be four numbers in [0, 1]"),
        "{e:?}"
    );
}

#[test]
fn the_first_directional_light_sets_the_shading_light() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.5f32]));
    let image = |h: &mut Host, lights: &[u64], shading: &str| {
        let (frame, camera) = h.lit_frame(volume, 3.0, lights);
        let r = shaded_renderer(h, frame, shading);
        h.d.commit(Subject::Object(frame));
        let pixels = h.pixels(frame);
        for o in [frame, camera, r] {
            h.d.release(o);
        }
        pixels
    };
    let light = |h: &mut Host, direction: [f32; 3], irradiance: f32| {
        let l = h.d.new_object(DataType::LIGHT, "directional");
        h.set(l, "direction", DataType::FLOAT32_VEC3, bytes(&direction));
        h.set(l, "irradiance", DataType::FLOAT32, bytes(&[irradiance]));
        h.d.commit(Subject::Object(l));
        l
    };
    let half = light(&mut h, [0.0, 0.0, -1.0], 0.5);
    // An environment light (not implemented) first: skipped for the
    // directional one.
    let hdri = h.d.new_object(DataType::LIGHT, "hdri");
    let centre = 4 * (12 * 24 + 12);
    // Lit samples (ambient occlusion ignores the direction) take the
    // light's strength; unlit ones show the transfer function as it is.
    let lit = image(&mut h, &[], "ao");
    let dimmed = image(&mut h, &[hdri, half], "ao");
    let (a, b) = (f32::from(lit[centre]), f32::from(dimmed[centre]));
    assert!(
        a > 40.0 && (b - 0.5 * a).abs() <= 2.0,
        "irradiance 0.5: {a} -> {b}"
    );
    let unlit = image(&mut h, &[], "none");
    assert_eq!(
        unlit,
        image(&mut h, &[hdri, half], "none"),
        "a light changed an unlit image"
    );
    // Shadows follow the light's direction.
    let from_left = light(&mut h, [1.0, 0.0, 0.0], 1.0);
    let from_right = light(&mut h, [-1.0, 0.0, 0.0], 1.0);
    let left = image(&mut h, &[from_left], "shadows");
    let right = image(&mut h, &[from_right], "shadows");
    assert!(
        same(&left, &right).is_err(),
        "the light's direction changes nothing"
    );
    let warnings = h.messages(Severity::Warning);
    assert!(
        warnings.len() == 1 && warnings[0].contains("does not implement light 'hdri'"),
        "{warnings:?}"
    );
    assert!(h.messages(Severity::Error).is_empty());
}

/// `anariDiscardFrame` stops the CPU reference between rows: a frame far
/// too slow to finish first reports the discard, not an image, and the
/// next render works.
#[test]
fn discard_stops_a_render_in_progress() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    let (frame, _camera) = h.frame(volume, 3.0);
    // 2048^2 with shadows: a minute on the CPU reference if it ran through.
    h.set(
        frame,
        "size",
        DataType::UINT32_VEC2,
        bytes(&[2048u32, 2048]),
    );
    shaded_renderer(&mut h, frame, "shadows");
    h.d.commit(Subject::Object(frame));
    h.d.render_frame(frame, None);
    h.d.discard_frame(frame);
    assert!(h.d.map_frame(frame, "channel.color").is_none());
    let errors = h.messages(Severity::Error);
    assert!(errors.iter().any(|e| e.contains("discarded")), "{errors:?}");
    assert_eq!(
        property(&mut h, frame, "numSamples"),
        Some(Property::Int32(0))
    );
    // A small render afterwards is whole.
    h.set(frame, "size", DataType::UINT32_VEC2, bytes(&[16u32, 16]));
    h.d.commit(Subject::Object(frame));
    h.d.render_frame(frame, None);
    assert!(h.d.map_frame(frame, "channel.color").is_some());
    h.d.unmap_frame(frame, "channel.color");
}

#[test]
fn a_background_gradient_through_the_device() {
    let mut h = Host::new();
    let field = h.field(|_| 0.0, None);
    let volume = h.volume(field);
    h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.0f32]));
    let (frame, _camera) = h.frame(volume, 3.0);
    // VTK's gradient: 1 x N of FLOAT32_VEC4, bottom color first; pynari's
    // samples give the same N colors as an ARRAY1D.
    for (kind, dims) in [
        (DataType::ARRAY2D, [1, 2, 1]),
        (DataType::ARRAY1D, [2, 1, 1]),
    ] {
        let r = h.d.new_object(DataType::RENDERER, "scivis");
        let gradient = h.array(
            kind,
            DataType::FLOAT32_VEC4,
            dims,
            &bytes(&[1.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0]),
        );
        h.set_object(r, "background", kind, gradient);
        h.d.release(gradient);
        h.d.commit(Subject::Object(r));
        h.set_object(frame, "renderer", DataType::RENDERER, r);
        h.d.commit(Subject::Object(frame));
        h.d.release(r);
        let pixels = h.pixels(frame);
        let size = common::device::SIZE as usize;
        let at = |y: usize| &pixels[4 * y * size..4 * y * size + 3];
        assert_eq!(at(0), [255, 0, 0], "{kind}: bottom row");
        assert_eq!(at(size - 1), [0, 0, 255], "{kind}: top row");
        assert!(h.messages(Severity::Error).is_empty(), "{kind}");
    }
}

/// A background image shows behind an empty world as it does behind a
/// volume that covers nothing, on both renderers: stretched over the frame
/// and sampled as `BackgroundImage::at` says.
#[test]
fn a_background_image_shows_behind_an_empty_world() {
    use anari_library_caveray::render::BackgroundImage;
    // A 2 x 2 checker of four colors, lower left first.
    let texels = [
        [1.0f32, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0, 1.0],
        [1.0, 1.0, 0.0, 1.0],
    ];
    let image = BackgroundImage::new(
        glam::UVec2::new(2, 2),
        texels.iter().map(|t| glam::Vec4::from_array(*t)).collect(),
    )
    .unwrap();
    let size = common::device::SIZE;
    let expected: Vec<u8> = (0..size * size)
        .flat_map(|i| {
            let c = image.at(i % size, i / size, glam::UVec2::splat(size));
            c.to_array().map(|x| (x * 255.0).round() as u8)
        })
        .collect();
    for backend in ["cpu", "gpu"] {
        let mut h = Host::on_backend(backend, Arc::new(|_s: Status| {}));
        let field = h.field(|_| 0.0, None);
        let volume = h.volume(field);
        h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.0f32]));
        let (frame, _camera) = h.frame(volume, 3.0);
        let r = h.d.new_object(DataType::RENDERER, "default");
        let flat: Vec<f32> = texels.iter().flatten().copied().collect();
        let array = h.array(
            DataType::ARRAY2D,
            DataType::FLOAT32_VEC4,
            [2, 2, 1],
            &bytes(&flat),
        );
        h.set_object(r, "background", DataType::ARRAY2D, array);
        h.d.release(array);
        h.d.commit(Subject::Object(r));
        h.set_object(frame, "renderer", DataType::RENDERER, r);
        h.d.commit(Subject::Object(frame));
        let behind_volume = h.pixels(frame);
        let empty = h.d.new_object(DataType::WORLD, "");
        h.d.commit(Subject::Object(empty));
        h.set_object(frame, "world", DataType::WORLD, empty);
        h.d.commit(Subject::Object(frame));
        let behind_nothing = h.pixels(frame);
        let worst = |a: &[u8]| {
            a.iter()
                .zip(&expected)
                .map(|(&x, &y)| x.abs_diff(y))
                .max()
                .unwrap()
        };
        assert!(worst(&behind_nothing) <= 1, "{backend}: empty world");
        assert!(worst(&behind_volume) <= 1, "{backend}: a clear volume");
        assert!(h.messages(Severity::Error).is_empty(), "{backend}");
    }
}

/// A property read with ANARI_WAIT while the frame still renders (the
/// frame's `duration` right after `anariRenderFrame`, as a benchmark host
/// reads it) waits for the render and answers; it once locked the frame's
/// slot twice and waited for ever.
#[test]
fn a_property_asked_for_with_wait_during_a_render_waits_for_it() {
    let (done, finished) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut h = Host::new();
        let field = h.field(|x| x as f32 / 3.0, None);
        let volume = h.volume(field);
        h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.3f32]));
        let (frame, _camera) = h.frame(volume, 3.0);
        // Long enough a render that it is still running when asked.
        shaded_renderer(&mut h, frame, "shadows+ao");
        h.set(frame, "size", DataType::UINT32_VEC2, bytes(&[512u32, 512]));
        h.d.commit(Subject::Object(frame));
        let mut answers = Vec::new();
        for name in ["duration", "numSamples"] {
            h.d.render_frame(frame, None);
            answers.push(property(&mut h, frame, name));
        }
        let _ = done.send((answers, h.errors()));
    });
    let (answers, errors) = finished
        .recv_timeout(std::time::Duration::from_secs(300))
        .expect("anariGetProperty with ANARI_WAIT during a render never returned");
    assert!(
        matches!(answers[0], Some(Property::Float32(s)) if s > 0.0),
        "{answers:?}"
    );
    // The second render of the unchanged frame is its second sample.
    assert_eq!(answers[1], Some(Property::Int32(2)));
    assert!(errors.is_empty(), "{errors:?}");
}
