//! Per-eye frames rendered in one re-projection pass
//! (ANARI_CAVERAY_FRAME_STEREO_PAIR): a host that renders each eye of a
//! wall as its own frame, one after the other, gets the first eye as its
//! own pass would make it and the second from the same pass, at once;
//! anything changed in between means a normal render; pairing can be
//! named per frame and switched off per device.

use crate::common;

use std::sync::{Arc, Mutex};

use anari_library_caveray::device::{DataType, Input, Severity, Status, Subject};
use anari_library_caveray::render::{dssim, ColorData, Frame};
use common::device::{bytes, same, Host, SIZE};
use glam::UVec2;

/// A wall at z = 2 seen from z = 4.5, as in device_stereo.rs.
const WALL: [[f32; 3]; 3] = [[-1.2, -1.2, 2.0], [1.2, -1.2, 2.0], [1.2, 1.2, 2.0]];
/// The eyes, 0.3 apart along the wall's rows.
const LEFT: [f32; 3] = [-0.05, -0.2, 4.5];
const RIGHT: [f32; 3] = [0.25, -0.2, 4.5];

struct Pair {
    h: Host,
    heard: Arc<Mutex<Vec<String>>>,
    volume: u64,
    left: u64,
    right: u64,
    cameras: [u64; 2],
}

impl Pair {
    /// A GPU device with a translucent ramp and one frame per eye, sharing
    /// world and renderer; `pairing` sets `pairStereoFrames`.
    fn new(pairing: bool) -> Self {
        let heard: Arc<Mutex<Vec<String>>> = Arc::default();
        let log = Arc::clone(&heard);
        let mut h = Host::reporting_to(Arc::new(move |s: Status| {
            if s.message.starts_with("stereo pair") {
                log.lock().unwrap().push(s.message);
            }
        }));
        h.d.set_param(Subject::Device, "backend", Input::String("gpu".into()));
        h.d.set_param(
            Subject::Device,
            "pairStereoFrames",
            Input::Bytes(DataType::BOOL, vec![u8::from(pairing)]),
        );
        h.d.commit(Subject::Device);
        let field = h.field(|x| 0.2 + x as f32 / 4.0, None);
        let volume = h.volume(field);
        h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.3f32]));
        h.d.commit(Subject::Object(volume));
        let list = h.array(
            DataType::ARRAY1D,
            DataType::VOLUME,
            [1, 1, 1],
            &bytes(&[volume as usize]),
        );
        let world = h.d.new_object(DataType::WORLD, "");
        h.set_object(world, "volume", DataType::ARRAY1D, list);
        h.d.commit(Subject::Object(world));
        let renderer = h.d.new_object(DataType::RENDERER, "default");
        h.d.commit(Subject::Object(renderer));
        let mut frames = [0; 2];
        let mut cameras = [0; 2];
        for (i, eye) in [LEFT, RIGHT].into_iter().enumerate() {
            let camera = h.d.new_object(DataType::CAMERA, "offAxis");
            for (name, v) in [
                ("lowerLeft", WALL[0]),
                ("lowerRight", WALL[1]),
                ("upperRight", WALL[2]),
                ("eye", eye),
            ] {
                h.set(camera, name, DataType::FLOAT32_VEC3, bytes(&v));
            }
            h.d.commit(Subject::Object(camera));
            let frame = h.d.new_object(DataType::FRAME, "");
            h.set(frame, "size", DataType::UINT32_VEC2, bytes(&[SIZE, SIZE]));
            h.set(
                frame,
                "channel.color",
                DataType::DATA_TYPE,
                bytes(&[DataType::UFIXED8_VEC4 as i32]),
            );
            h.set_object(frame, "world", DataType::WORLD, world);
            h.set_object(frame, "renderer", DataType::RENDERER, renderer);
            h.set_object(frame, "camera", DataType::CAMERA, camera);
            h.d.commit(Subject::Object(frame));
            frames[i] = frame;
            cameras[i] = camera;
        }
        h.d.release(list);
        h.d.release(renderer);
        Self {
            h,
            heard,
            volume,
            left: frames[0],
            right: frames[1],
            cameras,
        }
    }

    fn render(&mut self, frame: u64) -> Vec<u8> {
        self.h.pixels(frame)
    }

    fn heard(&self) -> Vec<String> {
        std::mem::take(&mut *self.heard.lock().unwrap())
    }

    fn move_eye(&mut self, camera: usize, eye: [f32; 3]) {
        let c = self.cameras[camera];
        self.h.set(c, "eye", DataType::FLOAT32_VEC3, bytes(&eye));
        self.h.d.commit(Subject::Object(c));
    }
}

fn frame(pixels: Vec<u8>) -> Frame {
    Frame {
        size: UVec2::splat(SIZE),
        color: ColorData::Rgba8(pixels),
        depth: None,
        hits: None,
        samples: 0,
    }
}

#[test]
fn per_eye_frames_render_in_one_pass_and_the_second_eye_is_kept() {
    // Each eye alone: pairing off.
    let mut alone = Pair::new(false);
    let (left, right) = (alone.render(alone.left), alone.render(alone.right));
    assert!(alone.heard().is_empty());

    let mut p = Pair::new(true);
    let paired_left = p.render(p.left);
    let heard = p.heard();
    assert_eq!(heard.len(), 1, "{heard:?}");
    assert!(heard[0].contains("in one re-projection pass"), "{heard:?}");
    let paired_right = p.render(p.right);
    let heard = p.heard();
    assert!(
        heard.len() == 1 && heard[0].contains("re-projected for it"),
        "{heard:?}"
    );
    // The first eye is its own pass, byte for byte; the second within the
    // re-projection's DSSIM bound.
    same(&paired_left, &left).unwrap();
    let d = dssim(&frame(paired_right.clone()), &frame(right.clone())).unwrap();
    let unmoved = dssim(&frame(left.clone()), &frame(right.clone())).unwrap();
    eprintln!("paired right eye: DSSIM {d:.4} (left as right {unmoved:.4})");
    assert!(d < 0.02 && d < 0.5 * unmoved, "DSSIM {d} vs {unmoved}");
    // The kept image is given once: rendering the right frame again with
    // nothing changed keeps it as any unchanged frame does.
    same(&p.render(p.right), &paired_right).unwrap();
    assert!(p.heard().is_empty());
    assert!(p.h.messages(Severity::Error).is_empty());
    assert!(p.h.messages(Severity::Warning).is_empty());
}

#[test]
fn a_change_between_the_eyes_means_a_normal_render() {
    let mut alone = Pair::new(false);
    alone.move_eye(1, [0.3, -0.2, 4.5]);
    let moved = alone.render(alone.right);

    let mut p = Pair::new(true);
    let _ = p.render(p.left);
    assert!(p.heard()[0].contains("in one re-projection pass"));
    // The head moved before the host got to the right eye: its kept image
    // is for the old eye and must not show.
    p.move_eye(1, [0.3, -0.2, 4.5]);
    let right = p.render(p.right);
    same(&right, &moved).unwrap();
    let heard = p.heard();
    assert!(
        heard.iter().all(|m| !m.contains("re-projected for it")),
        "{heard:?}"
    );

    // The volume changed in between: a normal render too.
    p.move_eye(1, RIGHT);
    p.move_eye(0, [-0.06, -0.2, 4.5]);
    let _ = p.render(p.left);
    let heard = p.heard();
    assert!(heard[0].contains("in one re-projection pass"), "{heard:?}");
    p.h.set(p.volume, "opacity", DataType::FLOAT32, bytes(&[0.5f32]));
    p.h.d.commit(Subject::Object(p.volume));
    let _ = p.render(p.right);
    let heard = p.heard();
    assert!(
        heard.iter().all(|m| !m.contains("re-projected for it")),
        "{heard:?}"
    );
}

#[test]
fn pairing_can_be_named_per_frame_and_is_refused_with_a_reason() {
    // Automatic pairing off, the partner named: still one pass.
    let mut p = Pair::new(false);
    let right = p.right;
    p.h.set_object(p.left, "stereoPartner", DataType::FRAME, right);
    p.h.d.commit(Subject::Object(p.left));
    let _ = p.render(p.left);
    assert!(p.heard()[0].contains("in one re-projection pass"));
    let _ = p.render(p.right);
    assert!(p.heard()[0].contains("re-projected for it"));
    // A named partner of another size is refused, and the host hears why.
    p.h.set(
        p.right,
        "size",
        DataType::UINT32_VEC2,
        bytes(&[SIZE, SIZE / 2]),
    );
    p.h.d.commit(Subject::Object(p.right));
    p.move_eye(0, [-0.06, -0.2, 4.5]);
    let _ = p.render(p.left);
    let warnings = p.h.messages(Severity::Warning);
    assert!(
        warnings.iter().any(
            |w| w.contains("renders alone: its stereoPartner") && w.contains("differs in size")
        ),
        "{warnings:?}"
    );
    // Frames naming each other are freed with the device (valgrind runs
    // the C host that does the same).
    p.h.set_object(p.right, "stereoPartner", DataType::FRAME, p.left);
    p.h.d.commit(Subject::Object(p.right));
    p.h.d.release(p.left);
    p.h.d.release(p.right);
    assert!(p.h.messages(Severity::Error).is_empty());
}

#[test]
fn the_cpu_reference_renders_each_eye_alone() {
    let mut p = Pair::new(true);
    p.h.d
        .set_param(Subject::Device, "backend", Input::String("cpu".into()));
    p.h.d.commit(Subject::Device);
    let _ = p.render(p.left);
    let _ = p.render(p.right);
    assert!(p.heard().is_empty());
}
