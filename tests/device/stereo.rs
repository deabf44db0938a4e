//! ANARI_KHR_CAMERA_STEREO on the perspective camera: `left` and `right`
//! shift the eye half the interpupillary distance along the camera's right
//! vector; `sideBySide` and `topBottom` put both eyes in one frame, each
//! exactly the image its own eye renders.

use crate::common;

use anari_library_caveray::device::{DataType, Input, Severity, StatusCode, Subject};
use common::device::{bytes, same, Host, SIZE};

/// A translucent ramp seen from z = 3, with the camera returned.
fn scene(h: &mut Host) -> (u64, u64) {
    let field = h.field(|x| 0.2 + x as f32 / 4.0, None);
    let volume = h.volume(field);
    let colors = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32_VEC3,
        [2, 1, 1],
        &bytes(&[1.0f32, 0.2, 0.1, 0.1, 0.3, 1.0]),
    );
    h.set_object(volume, "color", DataType::ARRAY1D, colors);
    h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.3f32]));
    h.d.release(colors);
    h.frame(volume, 3.0)
}

fn stereo(h: &mut Host, camera: u64, mode: &str, ipd: f32) {
    h.d.set_param(
        Subject::Object(camera),
        "stereoMode",
        Input::String(mode.into()),
    );
    h.set(
        camera,
        "interpupillaryDistance",
        DataType::FLOAT32,
        bytes(&[ipd]),
    );
    h.d.commit(Subject::Object(camera));
}

fn size(h: &mut Host, frame: u64, w: u32, hgt: u32) {
    h.set(frame, "size", DataType::UINT32_VEC2, bytes(&[w, hgt]));
    h.d.commit(Subject::Object(frame));
}

/// Rows `y0..y0 + rows` and columns `x0..x0 + cols` of an RGBA8 image
/// `width` wide.
fn crop(pixels: &[u8], width: u32, (x0, y0): (u32, u32), (cols, rows): (u32, u32)) -> Vec<u8> {
    (y0..y0 + rows)
        .flat_map(|y| {
            let start = 4 * (y * width + x0) as usize;
            pixels[start..start + 4 * cols as usize].to_vec()
        })
        .collect()
}

#[test]
fn left_and_right_move_the_eye_along_the_right_vector() {
    let mut h = Host::new();
    let (frame, camera) = scene(&mut h);
    let centre = h.pixels(frame);
    stereo(&mut h, camera, "left", 0.4);
    let left = h.pixels(frame);
    stereo(&mut h, camera, "right", 0.4);
    let right = h.pixels(frame);
    assert!(same(&left, &centre).is_err() && same(&left, &right).is_err());
    // The same eyes by hand: the camera moved 0.2 to each side.
    stereo(&mut h, camera, "none", 0.4);
    for (x, image) in [(-0.2f32, &left), (0.2, &right)] {
        h.set(
            camera,
            "position",
            DataType::FLOAT32_VEC3,
            bytes(&[x, 0.0, 3.0]),
        );
        h.d.commit(Subject::Object(camera));
        same(&h.pixels(frame), image).unwrap();
    }
    assert!(h.messages(Severity::Error).is_empty());
    assert!(h.messages(Severity::Warning).is_empty());
}

#[test]
fn side_by_side_and_top_bottom_hold_each_eye_as_it_renders_alone() {
    let mut h = Host::new();
    let (frame, camera) = scene(&mut h);
    let eye = |h: &mut Host, mode: &str| {
        stereo(h, camera, mode, 0.4);
        h.pixels(frame)
    };
    // Each eye alone at SIZE x SIZE.
    let left = eye(&mut h, "left");
    let right = eye(&mut h, "right");
    // Side by side in 2 SIZE x SIZE: left eye on the left.
    size(&mut h, frame, 2 * SIZE, SIZE);
    stereo(&mut h, camera, "sideBySide", 0.4);
    let pair = h.pixels_sized(frame, 2 * SIZE, SIZE);
    same(&crop(&pair, 2 * SIZE, (0, 0), (SIZE, SIZE)), &left).unwrap();
    same(&crop(&pair, 2 * SIZE, (SIZE, 0), (SIZE, SIZE)), &right).unwrap();
    // One above the other in SIZE x 2 SIZE: the left eye on top (the
    // upper rows; images start at the lower left).
    size(&mut h, frame, SIZE, 2 * SIZE);
    stereo(&mut h, camera, "topBottom", 0.4);
    let pair = h.pixels_sized(frame, SIZE, 2 * SIZE);
    same(&crop(&pair, SIZE, (0, SIZE), (SIZE, SIZE)), &left).unwrap();
    same(&crop(&pair, SIZE, (0, 0), (SIZE, SIZE)), &right).unwrap();
    // With no distance between the eyes both halves are the same.
    stereo(&mut h, camera, "topBottom", 0.0);
    let pair = h.pixels_sized(frame, SIZE, 2 * SIZE);
    same(
        &crop(&pair, SIZE, (0, SIZE), (SIZE, SIZE)),
        &crop(&pair, SIZE, (0, 0), (SIZE, SIZE)),
    )
    .unwrap();
    assert!(h.messages(Severity::Error).is_empty());
}

#[test]
fn bad_stereo_parameters_are_refused_at_commit_and_the_extension_is_reported() {
    let mut h = Host::new();
    let (_frame, camera) = scene(&mut h);
    stereo(&mut h, camera, "crossEyed", 0.06);
    let errors = h.messages(Severity::Error);
    assert!(
        errors.iter().any(|e| e.contains(
            "stereoMode \"crossEyed\" is not one of none, left, right, sideBySide, topBottom"
        )),
        "{errors:?}"
    );
    stereo(&mut h, camera, "left", -0.06);
    let errors = h.messages(Severity::Error);
    assert!(
        errors.iter().any(|e| e
            .contains("interpupillaryDistance must be a finite number of at least 0, got -0.06")),
        "{errors:?}"
    );
    let info = anari_library_caveray::device::info::EXTENSIONS;
    assert!(info.contains(&"ANARI_KHR_CAMERA_STEREO"));
}

/// The one error since the last ask, which must be `code`'s.
fn one_error(h: &mut Host, code: StatusCode) -> String {
    let errors = h.errors();
    match &errors[..] {
        [(c, m)] if *c == code => m.clone(),
        _ => panic!("expected one {code:?} error, got {errors:?}"),
    }
}

/// Whether the frame renders; its error if not.
fn try_pixels(h: &mut Host, frame: u64) -> Result<Vec<u8>, String> {
    h.d.render_frame(frame, None);
    match h.d.map_frame(frame, "channel.color") {
        Some(mapped) => {
            // SAFETY: a mapped RGBA8 frame of SIZE x SIZE pixels, valid
            // until unmap.
            let pixels =
                unsafe { std::slice::from_raw_parts(mapped.ptr, (4 * SIZE * SIZE) as usize) }
                    .to_vec();
            h.d.unmap_frame(frame, "channel.color");
            Ok(pixels)
        }
        None => {
            // The render says why, and the map that it failed.
            let errors = h.errors();
            match &errors[..] {
                [(StatusCode::InvalidOperation, _), (StatusCode::InvalidOperation, map)]
                    if map.contains("the last render failed") => {}
                _ => panic!("expected the render's and the map's errors, got {errors:?}"),
            }
            Err(errors[0].1.clone())
        }
    }
}

#[test]
fn an_interpupillary_distance_is_the_hosts_length_and_only_one_that_cannot_give_an_image_is_refused(
) {
    let mut h = Host::new();
    let (frame, perspective) = scene(&mut h);
    let off_axis = h.d.new_object(DataType::CAMERA, "offAxis");
    for (name, corner) in [
        ("lowerLeft", [-1.0f32, -1.0, 0.0]),
        ("lowerRight", [1.0, -1.0, 0.0]),
        ("upperRight", [1.0, 1.0, 0.0]),
        ("eye", [0.0, 0.0, 3.0]),
    ] {
        h.set(off_axis, name, DataType::FLOAT32_VEC3, bytes(&corner));
    }
    // The tables tell hosts: at least 0, no maximum (a length in the
    // host's units; no bound fits every scene).
    for subtype in ["perspective", "offAxis"] {
        let range = anari_library_caveray::device::info::param(
            DataType::CAMERA,
            subtype,
            "interpupillaryDistance",
        )
        .and_then(|p| p.range);
        assert_eq!(range, Some((0.0, f32::INFINITY)), "{subtype}");
    }
    for camera in [perspective, off_axis] {
        h.set_object(frame, "camera", DataType::CAMERA, camera);
        h.d.commit(Subject::Object(frame));
        stereo(&mut h, camera, "left", 0.06);
        let good = h.pixels(frame);
        // Eyes 50 units apart around a scene 2 units wide: far apart, and
        // an image all the same (the off-axis eyes stay in front of the
        // wall, beyond its sides).
        stereo(&mut h, camera, "right", 50.0);
        try_pixels(&mut h, frame).unwrap();
        assert!(h.errors().is_empty());
        for bad in [-0.06f32, f32::NAN, f32::INFINITY] {
            stereo(&mut h, camera, "left", bad);
            let e = one_error(&mut h, StatusCode::InvalidArgument);
            assert!(
                e.contains(&format!(
                    "interpupillaryDistance must be a finite number of at least 0, got {bad:?}"
                )),
                "{e}"
            );
        }
        // Finite, but the eye 5e29 out: the world spans no float step.
        stereo(&mut h, camera, "left", 1e30);
        assert!(h.errors().is_empty());
        let e = try_pixels(&mut h, frame).unwrap_err();
        assert!(
            e.contains("interpupillaryDistance 1e30 puts an eye at")
                && e.contains("no image of it can be made"),
            "{e}"
        );
        stereo(&mut h, camera, "left", 0.06);
        same(&h.pixels(frame), &good).unwrap();
        assert!(h.errors().is_empty());
    }
    // Eyes apart along the wall's normal: a distance past twice the eye's
    // own puts the far eye behind the wall.
    h.set(
        off_axis,
        "eyeAxis",
        DataType::FLOAT32_VEC3,
        bytes(&[0.0f32, 0.0, 1.0]),
    );
    stereo(&mut h, off_axis, "left", 10.0);
    let e = try_pixels(&mut h, frame).unwrap_err();
    assert!(
        e.contains("interpupillaryDistance 10 along eyeAxis puts the left eye at (0, 0, -2): eye is on or behind the wall"),
        "{e}"
    );
    stereo(&mut h, off_axis, "left", 4.0);
    try_pixels(&mut h, frame).unwrap();
    assert!(h.errors().is_empty());
}

#[test]
fn a_split_stereo_frame_one_pixel_across_is_refused_at_render() {
    let mut h = Host::new();
    let (frame, camera) = scene(&mut h);
    for (mode, (w, hgt), side) in [
        ("sideBySide", (1, 8), "wide"),
        ("topBottom", (8, 1), "high"),
    ] {
        stereo(&mut h, camera, mode, 0.1);
        size(&mut h, frame, w, hgt);
        h.d.render_frame(frame, None);
        let e = one_error(&mut h, StatusCode::InvalidOperation);
        assert!(
            e.contains(&format!(
                "stereoMode {mode} splits the frame between the eyes, so it must be at least 2 pixels {side}; this frame is {w}x{hgt}"
            )),
            "{e}"
        );
        // The other way round, each eye has its pixels.
        size(&mut h, frame, hgt, w);
        h.pixels_sized(frame, hgt, w);
        size(&mut h, frame, 2, 2);
        h.pixels_sized(frame, 2, 2);
        assert!(h.errors().is_empty());
    }
}

/// A frame's color as a `Frame` for SSIM.
fn as_frame(pixels: Vec<u8>, w: u32, hgt: u32) -> anari_library_caveray::render::Frame {
    anari_library_caveray::render::Frame {
        size: glam::UVec2::new(w, hgt),
        color: anari_library_caveray::render::ColorData::Rgba8(pixels),
        depth: None,
        hits: None,
        samples: 0,
    }
}

#[test]
fn side_by_side_on_the_gpu_is_one_reprojection_pass_close_to_two() {
    use anari_library_caveray::device::Status;
    use anari_library_caveray::render::{dssim, ssim};
    use std::sync::{Arc, Mutex};
    let heard: Arc<Mutex<Vec<String>>> = Arc::default();
    let log = Arc::clone(&heard);
    let mut h = Host::reporting_to(Arc::new(move |s: Status| {
        if s.severity == Severity::Info {
            log.lock().unwrap().push(s.message);
        }
    }));
    let infos = || std::mem::take(&mut *heard.lock().unwrap());
    h.d.set_param(Subject::Device, "backend", Input::String("gpu".into()));
    h.d.commit(Subject::Device);
    let (frame, camera) = scene(&mut h);
    let n = 2 * SIZE;
    size(&mut h, frame, n, n);
    let eye = |h: &mut Host, mode: &str| {
        stereo(h, camera, mode, 0.3);
        h.pixels_sized(frame, n, n)
    };
    let left = eye(&mut h, "left");
    let right = eye(&mut h, "right");
    size(&mut h, frame, 2 * n, n);
    stereo(&mut h, camera, "sideBySide", 0.3);
    let pair = h.pixels_sized(frame, 2 * n, n);
    let heard = infos();
    assert!(
        heard
            .iter()
            .any(|m| m.contains("stereo frame: both eyes in one re-projection pass")),
        "{heard:?}"
    );
    let half = |x0| as_frame(crop(&pair, 2 * n, (x0, 0), (n, n)), n, n);
    let s = ssim(&half(0), &as_frame(left.clone(), n, n)).unwrap();
    assert!(s > 0.98, "left eye: SSIM {s} against its own pass");
    let d = dssim(&half(n), &as_frame(right.clone(), n, n)).unwrap();
    let unmoved = dssim(&as_frame(left, n, n), &as_frame(right, n, n)).unwrap();
    eprintln!(
        "sideBySide on the GPU: left SSIM {s:.5}, right DSSIM {d:.4}, left as right {unmoved:.4}"
    );
    assert!(
        d < 0.02 && d < unmoved,
        "right eye: DSSIM {d} (left as right {unmoved})"
    );
    // A depth channel keeps the single pass: the right eye's depth comes
    // from the layers.
    h.set(
        frame,
        "channel.depth",
        DataType::DATA_TYPE,
        bytes(&[DataType::FLOAT32 as i32]),
    );
    h.d.commit(Subject::Object(frame));
    let _ = h.pixels_sized(frame, 2 * n, n);
    let heard = infos();
    assert!(
        heard
            .iter()
            .any(|m| m.contains("stereo frame: both eyes in one re-projection pass")),
        "{heard:?}"
    );
    assert!(h.messages(Severity::Error).is_empty());
}

/// An offAxis camera on a 2.4 x 2.4 wall at z = 2, the eyes centred at
/// (0.1, -0.2, 4.5), replacing the frame's camera.
fn wall_camera(h: &mut Host, frame: u64) -> u64 {
    let camera = h.d.new_object(DataType::CAMERA, "offAxis");
    for (name, v) in [
        ("lowerLeft", [-1.2f32, -1.2, 2.0]),
        ("lowerRight", [1.2, -1.2, 2.0]),
        ("upperRight", [1.2, 1.2, 2.0]),
        ("eye", [0.1, -0.2, 4.5]),
    ] {
        h.set(camera, name, DataType::FLOAT32_VEC3, bytes(&v));
    }
    h.d.commit(Subject::Object(camera));
    h.set_object(frame, "camera", DataType::CAMERA, camera);
    h.d.commit(Subject::Object(frame));
    camera
}

#[test]
fn an_off_axis_wall_camera_takes_the_same_stereo_modes() {
    let mut h = Host::new();
    let (frame, _) = scene(&mut h);
    let camera = wall_camera(&mut h, frame);
    stereo(&mut h, camera, "left", 0.3);
    let left = h.pixels(frame);
    stereo(&mut h, camera, "right", 0.3);
    let right = h.pixels(frame);
    // By hand: the eye 0.15 along the wall's rows to each side.
    stereo(&mut h, camera, "none", 0.3);
    for (x, image) in [(-0.05f32, &left), (0.25, &right)] {
        h.set(
            camera,
            "eye",
            DataType::FLOAT32_VEC3,
            bytes(&[x, -0.2, 4.5]),
        );
        h.d.commit(Subject::Object(camera));
        same(&h.pixels(frame), image).unwrap();
    }
    // Side by side: each half its eye.
    h.set(
        camera,
        "eye",
        DataType::FLOAT32_VEC3,
        bytes(&[0.1f32, -0.2, 4.5]),
    );
    size(&mut h, frame, 2 * SIZE, SIZE);
    stereo(&mut h, camera, "sideBySide", 0.3);
    let pair = h.pixels_sized(frame, 2 * SIZE, SIZE);
    same(&crop(&pair, 2 * SIZE, (0, 0), (SIZE, SIZE)), &left).unwrap();
    same(&crop(&pair, 2 * SIZE, (SIZE, 0), (SIZE, SIZE)), &right).unwrap();
    assert!(h.messages(Severity::Error).is_empty());
}

#[test]
fn off_axis_pairs_reproject_for_level_turned_and_rolled_heads() {
    use anari_library_caveray::device::Status;
    use anari_library_caveray::render::{dssim, ssim};
    use std::sync::{Arc, Mutex};
    let heard: Arc<Mutex<Vec<String>>> = Arc::default();
    let log = Arc::clone(&heard);
    let mut h = Host::reporting_to(Arc::new(move |s: Status| {
        if s.severity == Severity::Info && s.message.starts_with("stereo frame") {
            log.lock().unwrap().push(s.message);
        }
    }));
    h.d.set_param(Subject::Device, "backend", Input::String("gpu".into()));
    h.d.commit(Subject::Device);
    let (frame, _) = scene(&mut h);
    let camera = wall_camera(&mut h, frame);
    let n = 2 * SIZE;
    // Level, turned 37 degrees (the baseline leaves the wall's plane),
    // rolled 15 degrees (it tilts in the plane).
    for axis in [[1.0f32, 0.0, 0.0], [0.8, 0.0, 0.6], [0.966, 0.259, 0.0]] {
        h.set(camera, "eyeAxis", DataType::FLOAT32_VEC3, bytes(&axis));
        size(&mut h, frame, n, n);
        stereo(&mut h, camera, "left", 0.3);
        let left = as_frame(h.pixels_sized(frame, n, n), n, n);
        stereo(&mut h, camera, "right", 0.3);
        let right = as_frame(h.pixels_sized(frame, n, n), n, n);
        size(&mut h, frame, 2 * n, n);
        stereo(&mut h, camera, "sideBySide", 0.3);
        let pair = h.pixels_sized(frame, 2 * n, n);
        let heard = std::mem::take(&mut *heard.lock().unwrap());
        assert!(
            heard.iter().any(|m| m.contains("one re-projection pass")),
            "{axis:?}: {heard:?}"
        );
        let half = |x0| as_frame(crop(&pair, 2 * n, (x0, 0), (n, n)), n, n);
        let s = ssim(&half(0), &left).unwrap();
        let d = dssim(&half(n), &right).unwrap();
        let unmoved = dssim(&left, &right).unwrap();
        eprintln!(
            "eyeAxis {axis:?}: left SSIM {s:.5}, right DSSIM {d:.4}, left as right {unmoved:.4}"
        );
        assert!(s > 0.98, "{axis:?}: left SSIM {s}");
        assert!(
            d < 0.03 && d < 0.5 * unmoved,
            "{axis:?}: DSSIM {d} vs {unmoved}"
        );
    }
    assert!(h.messages(Severity::Error).is_empty());
}
