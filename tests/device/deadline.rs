//! Frames with a deadline (ANARI_CAVERAY_FRAME_DEADLINE) in the device
//! model: bad deadlines and warps are refused at commit with their
//! reasons and the frame stays usable; the first frame shows the
//! background by its deadline, a still camera then gets its own image,
//! and a moved camera the newest image warped (of a grid and of a mesh);
//! a stereo camera is refused for a deadline frame; whole renders have no
//! deadline properties.

use crate::common;

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anari_library_caveray::device::{DataType, Input, Property, Severity, Status, Subject};
use common::device::{bytes, Host};

fn field(h: &mut Host) -> u64 {
    h.field(|x| x as f32 / 3.0, None)
}

fn deadline(h: &mut Host, frame: u64, ms: f32, warp: &str) {
    h.set(frame, "caveray.deadline", DataType::FLOAT32, bytes(&[ms]));
    h.d.set_param(
        Subject::Object(frame),
        "caveray.warp",
        Input::String(warp.into()),
    );
    h.d.commit(Subject::Object(frame));
}

/// (age in ms, warp) of the frame's last render, waiting for it.
fn shown(h: &mut Host, frame: u64) -> Option<(f32, String)> {
    let age = match h
        .d
        .property(Subject::Object(frame), "caveray.imageAge", true)?
    {
        Property::Float32(a) => a,
        _ => return None,
    };
    let warp = match h.d.property(Subject::Object(frame), "caveray.warp", true)? {
        Property::Text(t) => t.to_string_lossy().into_owned(),
        _ => return None,
    };
    Some((age, warp))
}

#[test]
fn bad_deadlines_and_warps_are_refused_with_their_reasons() {
    let mut h = Host::new();
    let f = field(&mut h);
    let v = h.volume(f);
    let (frame, _camera) = h.frame(v, 3.0);
    for (ms, warp, want) in [
        (
            -1.0,
            "quad",
            "caveray.deadline must be 0 (none) to 10000 ms, got -1",
        ),
        (
            f32::NAN,
            "quad",
            "caveray.deadline must be 0 (none) to 10000 ms, got NaN",
        ),
        (20_000.0, "quad", "got 20000"),
        (
            5.0,
            "sideways",
            "caveray.warp: unknown warp 'sideways'; expected none, quad, grid or layers",
        ),
    ] {
        deadline(&mut h, frame, ms, warp);
        let errors = h.messages(Severity::Error);
        assert!(
            errors.iter().any(|e| e.contains(want)),
            "{ms} ms, {warp}: {errors:?}"
        );
    }
    // A good value makes the frame usable again, and a whole render has no
    // deadline properties.
    deadline(&mut h, frame, 0.0, "quad");
    assert!(h.messages(Severity::Error).is_empty());
    let pixels = h.pixels(frame);
    assert!(pixels.iter().any(|&p| p > 0));
    assert!(
        shown(&mut h, frame).is_none(),
        "a whole render has no caveray.imageAge"
    );
}

#[test]
fn a_deadline_frame_shows_the_background_then_its_own_image_then_a_warp() {
    background_then_own_image_then_warp(field);
}

/// The same of an unstructured field (the grid's cells as tetrahedra).
#[test]
fn a_deadline_frame_of_a_mesh_shows_its_own_image_then_a_warp() {
    background_then_own_image_then_warp(|h| h.mesh_field(|x| x as f32 / 3.0));
}

/// The same of an AMR field of two levels.
#[test]
fn a_deadline_frame_of_an_amr_field_shows_its_own_image_then_a_warp() {
    background_then_own_image_then_warp(|h| h.amr_field(|x| x as f32 / 3.0, true));
}

/// The same of a NanoVDB grid (the camera inside its fog).
#[test]
fn a_deadline_frame_of_a_nanovdb_grid_shows_its_own_image_then_a_warp() {
    let Some(written) = crate::common::nanovdb::grids() else {
        return;
    };
    let blob = written.blob("fog8");
    background_then_own_image_then_warp(|h| h.nanovdb_field(&blob, None));
}

fn background_then_own_image_then_warp(field: impl Fn(&mut Host) -> u64) {
    // The presenter speaks from its own thread, through the reporter.
    let heard = Arc::new(Mutex::new(Vec::<String>::new()));
    let sink = Arc::clone(&heard);
    let mut h = Host::reporting_to(Arc::new(move |s: Status| {
        if (s.severity as i32) <= Severity::Info as i32 {
            sink.lock().unwrap().push(s.message);
        }
    }));
    let f = field(&mut h);
    let v = h.volume(f);
    let (frame, camera) = h.frame(v, 3.0);
    deadline(&mut h, frame, 0.001, "layers");
    // A large whole render first keeps the render thread busy: the deadline
    // frame's own render waits behind it, so by its deadline there is no
    // image at all.
    let (slow, _slow_camera) = h.frame(v, 3.0);
    h.set(slow, "size", DataType::UINT32_VEC2, bytes(&[4096u32, 4096]));
    h.d.commit(Subject::Object(slow));
    h.d.render_frame(slow, None);
    h.pixels(frame);
    assert_eq!(shown(&mut h, frame), Some((-1.0, "none".into())));
    h.d.discard_frame(slow);
    let infos = heard.lock().unwrap().join("\n");
    assert!(infos.contains("no image has been rendered yet"), "{infos}");

    // The same camera again until its own image is done.
    let start = Instant::now();
    let (age, warp) = loop {
        let still = h.pixels(frame);
        let s = shown(&mut h, frame).unwrap();
        if s.1 == "none" && s.0 >= 0.0 {
            assert!(
                still.iter().any(|&p| p > 0),
                "its own image shows the volume"
            );
            break s;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no image after a minute"
        );
        std::thread::sleep(Duration::from_millis(5));
    };
    assert!(age >= 0.0 && warp == "none");

    // A moved camera: the newest image, warped, while its own render
    // waits behind the slow one again (a deadline the warp can meet).
    deadline(&mut h, frame, 200.0, "layers");
    h.set(
        camera,
        "position",
        DataType::FLOAT32_VEC3,
        bytes(&[0.3f32, 0.0, 3.0]),
    );
    h.d.commit(Subject::Object(camera));
    h.d.render_frame(slow, None);
    h.pixels(frame);
    h.d.discard_frame(slow);
    let (age, warp) = shown(&mut h, frame).unwrap();
    assert_eq!(warp, "layers");
    assert!(
        age > 0.0,
        "the warped image is older than this render: {age}"
    );
    assert!(h.messages(Severity::Warning).is_empty());
    assert!(h.messages(Severity::Error).is_empty());
}

#[test]
fn a_stereo_camera_cannot_have_a_deadline() {
    let mut h = Host::new();
    let f = field(&mut h);
    let v = h.volume(f);
    let (frame, camera) = h.frame(v, 3.0);
    h.d.set_param(
        Subject::Object(camera),
        "stereoMode",
        Input::String("sideBySide".into()),
    );
    h.d.commit(Subject::Object(camera));
    deadline(&mut h, frame, 5.0, "quad");
    h.d.render_frame(frame, None);
    let errors = h.messages(Severity::Error).join("\n");
    assert!(
        errors.contains("shows one view: set the camera's stereoMode to none"),
        "{errors}"
    );
    // Still usable: without stereo it renders.
    h.d.set_param(
        Subject::Object(camera),
        "stereoMode",
        Input::String("none".into()),
    );
    h.d.commit(Subject::Object(camera));
    h.pixels(frame);
    assert!(shown(&mut h, frame).is_some());
    assert!(h.messages(Severity::Error).is_empty());
}

#[test]
fn on_the_gpu_backend_deadline_frames_warp_with_a_gpu_of_their_own() {
    let heard = Arc::new(Mutex::new(Vec::<String>::new()));
    let sink = Arc::clone(&heard);
    let mut h = Host::reporting_to(Arc::new(move |s: Status| {
        sink.lock().unwrap().push(s.message);
    }));
    h.d.set_param(Subject::Device, "backend", Input::String("gpu".into()));
    h.d.commit(Subject::Device);
    let f = field(&mut h);
    let v = h.volume(f);
    let (frame, camera) = h.frame(v, 3.0);
    deadline(&mut h, frame, 5.0, "grid");
    // Move the camera a little each frame until warps have run on the
    // presenter's own GPU.
    let start = Instant::now();
    let mut x = 0.0f32;
    let mut on_gpu = 0;
    while on_gpu < 3 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no GPU warps: {:?}",
            heard.lock().unwrap()
        );
        x += 0.01;
        h.set(
            camera,
            "position",
            DataType::FLOAT32_VEC3,
            bytes(&[x, 0.0, 3.0]),
        );
        h.d.commit(Subject::Object(camera));
        let pixels = h.pixels(frame);
        let opened = heard
            .lock()
            .unwrap()
            .iter()
            .any(|m| m.contains("deadline frames warp with GPU"));
        if let Some((age, warp)) = shown(&mut h, frame) {
            if opened && age > 0.0 && warp == "grid" {
                assert!(
                    pixels.iter().any(|&p| p > 0),
                    "a GPU-warped frame shows the volume"
                );
                on_gpu += 1;
            }
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(h.messages(Severity::Error).is_empty());
}

#[test]
fn a_device_released_while_its_frames_present_waits_for_them() {
    // The host may unload the library right after the release: the
    // presenters (and the background render) must be done by then. The
    // completion callback of each presented frame has run when the
    // release returns.
    let done = Arc::new(Mutex::new(0));
    let mut h = Host::new();
    let f = field(&mut h);
    let v = h.volume(f);
    let (frame, camera) = h.frame(v, 3.0);
    deadline(&mut h, frame, 200.0, "quad");
    for x in [0.0f32, 0.1, 0.2] {
        h.set(
            camera,
            "position",
            DataType::FLOAT32_VEC3,
            bytes(&[x, 0.0, 3.0]),
        );
        h.d.commit(Subject::Object(camera));
        let count = Arc::clone(&done);
        h.d.render_frame(frame, Some(Box::new(move || *count.lock().unwrap() += 1)));
    }
    drop(h);
    assert_eq!(*done.lock().unwrap(), 3, "every presented frame completed");
}

/// A world of one sphere of radius 0.5 at the origin, in white.
fn sphere_world(h: &mut Host) -> u64 {
    let g = h.d.new_object(DataType::GEOMETRY, "sphere");
    let at = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32_VEC3,
        [1, 1, 1],
        &bytes(&[0.0f32, 0.0, 0.0]),
    );
    h.set_object(g, "vertex.position", DataType::ARRAY1D, at);
    h.set(g, "radius", DataType::FLOAT32, bytes(&[0.5f32]));
    h.d.commit(Subject::Object(g));
    let m = h.d.new_object(DataType::MATERIAL, "matte");
    h.set(
        m,
        "color",
        DataType::FLOAT32_VEC3,
        bytes(&[1.0f32, 1.0, 1.0]),
    );
    h.d.commit(Subject::Object(m));
    let s = h.d.new_object(DataType::SURFACE, "");
    h.set_object(s, "geometry", DataType::GEOMETRY, g);
    h.set_object(s, "material", DataType::MATERIAL, m);
    h.d.commit(Subject::Object(s));
    let world = h.d.new_object(DataType::WORLD, "");
    h.set_objects(world, "surface", DataType::SURFACE, &[s]);
    h.d.commit(Subject::Object(world));
    world
}

#[test]
fn a_world_of_surfaces_is_warped_by_the_grid_and_the_layers() {
    // The GPU's grid warp captures as its layers warp does, without layers.
    for (backend, warp) in [("cpu", "grid"), ("cpu", "layers"), ("gpu", "layers")] {
        surfaces_warped_on(backend, warp);
    }
}

fn surfaces_warped_on(backend: &str, warp: &str) {
    let mut h = Host::on_backend(backend, Arc::new(|_| {}));
    let world = sphere_world(&mut h);
    let f = field(&mut h);
    let v = h.volume(f);
    let (frame, camera) = h.frame(v, 3.0);
    h.set_object(frame, "world", DataType::WORLD, world);
    h.d.commit(Subject::Object(frame));
    deadline(&mut h, frame, 500.0, warp);
    // Its own image once the background render is done: the sphere, white
    // at the centre.
    let start = Instant::now();
    let own = loop {
        let p = h.pixels(frame);
        let s = shown(&mut h, frame).unwrap();
        if s.1 == "none" && s.0 >= 0.0 {
            break p;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no image after a minute"
        );
        std::thread::sleep(Duration::from_millis(5));
    };
    let centre = |p: &[u8]| {
        let i = 4
            * (common::device::SIZE / 2 * common::device::SIZE + common::device::SIZE / 2) as usize;
        p[i]
    };
    assert!(centre(&own) > 200, "the sphere's centre: {}", centre(&own));
    // A camera moved while a large render keeps the render thread busy:
    // the sphere's image, warped to it by the grid.
    let (slow, _slow_camera) = h.frame(v, 3.0);
    h.set(slow, "size", DataType::UINT32_VEC2, bytes(&[4096u32, 4096]));
    h.d.commit(Subject::Object(slow));
    h.set(
        camera,
        "position",
        DataType::FLOAT32_VEC3,
        bytes(&[0.3f32, 0.0, 3.0]),
    );
    h.d.commit(Subject::Object(camera));
    h.d.render_frame(slow, None);
    let warped = h.pixels(frame);
    h.d.discard_frame(slow);
    let (age, shown_by) = shown(&mut h, frame).unwrap();
    assert_eq!(shown_by, warp);
    assert!(
        age > 0.0,
        "the warped image is older than this render: {age}"
    );
    // Still the sphere (the background is black), seen from the side now.
    assert!(
        centre(&warped) > 100,
        "the warped sphere's centre: {}",
        centre(&warped)
    );
    let moved = own.iter().zip(&warped).filter(|(a, b)| a != b).count();
    assert!(moved > 0, "the warp moved nothing");
    assert!(h.messages(Severity::Error).is_empty());
}
