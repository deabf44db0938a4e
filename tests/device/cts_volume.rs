//! The conformance tool's ten volume cases, as it builds them (HOSTS.md,
//! docs/hosts.md): a 3^3 field of the distance from the grid's centre,
//! placed at origin -1 with spacing 2/3, a transfer function varied one
//! parameter at a time, the camera placed from the world's `bounds`, colour
//! in sRGB and depth scaled by twice the bounds' diagonal. Each case is
//! scored by the tool's rule (SSIM >= 0.7, PSNR >= 20 dB) with the GPU's
//! image against the CPU's, and the cases with a closed-form answer are
//! checked against it.

use std::sync::Arc;

use anari_library_caveray::device::{DataType, Property, Severity, Status, Subject};
use glam::Vec3;

use crate::common::cts::{score, MIN_PSNR, MIN_SSIM};
use crate::common::device::{bytes, Host};

const SIZE: u32 = 64;

/// One case: the parameter it varies and the value it gives it.
#[derive(Clone, Copy, Debug)]
enum Case {
    Base,
    Filter(&'static str),
    NoOrigin,
    Spacing,
    ValueRange,
    ColorVec3,
    ColorVec4,
    OpacityScalar,
    UnitDistance,
}

const CASES: [Case; 10] = [
    Case::Base,
    Case::Filter("nearest"),
    Case::Filter("linear"),
    Case::NoOrigin,
    Case::Spacing,
    Case::ValueRange,
    Case::ColorVec3,
    Case::ColorVec4,
    Case::OpacityScalar,
    Case::UnitDistance,
];

struct Images {
    /// RGBA8, sRGB, lower-left first.
    color: Vec<u8>,
    /// As the tool draws depth: grey = depth / scale, 255 where infinite.
    depth: Vec<u8>,
    raw_depth: Vec<f32>,
    eye: Vec3,
}

fn render(backend: &str, case: Case) -> Images {
    let mut h = Host::on_backend(backend, Arc::new(|_s: Status| {}));
    // The field the tool makes for 3^3: distance from the centre of a grid
    // spread over [-1, 1]^3, though spacing 2/3 places it on [-1, 1/3]^3.
    let at = |i: u32| i as f32 - 1.0;
    let voxels: Vec<f32> = (0..27u32)
        .map(|i| Vec3::new(at(i % 3), at(i / 3 % 3), at(i / 9)).length())
        .collect();
    let data = h.array(
        DataType::ARRAY3D,
        DataType::FLOAT32,
        [3, 3, 3],
        &bytes(&voxels),
    );
    let field = h.d.new_object(DataType::SPATIAL_FIELD, "structuredRegular");
    h.set_object(field, "data", DataType::ARRAY3D, data);
    h.d.release(data);
    let origin = match case {
        Case::NoOrigin => None,
        _ => Some([-1.0f32; 3]),
    };
    if let Some(o) = origin {
        h.set(field, "origin", DataType::FLOAT32_VEC3, bytes(&o));
    }
    let spacing = match case {
        Case::Spacing => [0.01f32, 0.02, 0.5],
        _ => [2.0 / 3.0; 3],
    };
    h.set(field, "spacing", DataType::FLOAT32_VEC3, bytes(&spacing));
    if let Case::Filter(f) = case {
        h.d.set_param(
            Subject::Object(field),
            "filter",
            anari_library_caveray::device::Input::String(f.into()),
        );
    }
    h.d.commit(Subject::Object(field));

    let volume = h.volume(field);
    match case {
        Case::ColorVec3 => h.set(
            volume,
            "color",
            DataType::FLOAT32_VEC3,
            bytes(&[1.0f32, 0.75, 0.0]),
        ),
        Case::ColorVec4 => h.set(
            volume,
            "color",
            DataType::FLOAT32_VEC4,
            bytes(&[1.0f32, 0.75, 0.0, 0.5]),
        ),
        _ => {
            let colors = [0.25f32, 0.9, 0.2, 0.9, 0.1, 0.0, 0.0, 0.0, 0.7];
            let a = h.array(
                DataType::ARRAY1D,
                DataType::FLOAT32_VEC3,
                [3, 1, 1],
                &bytes(&colors),
            );
            h.set_object(volume, "color", DataType::ARRAY1D, a);
            h.d.release(a);
        }
    }
    match case {
        Case::OpacityScalar => h.set(volume, "opacity", DataType::FLOAT32, bytes(&[1.0f32])),
        _ => {
            let a = h.array(
                DataType::ARRAY1D,
                DataType::FLOAT32,
                [3, 1, 1],
                &bytes(&[0.25f32, 0.7, 1.0]),
            );
            h.set_object(volume, "opacity", DataType::ARRAY1D, a);
            h.d.release(a);
        }
    }
    if let Case::ValueRange = case {
        h.set(
            volume,
            "valueRange",
            DataType::FLOAT32_VEC2,
            bytes(&[0.25f32, 0.75]),
        );
    }
    if let Case::UnitDistance = case {
        h.set(volume, "unitDistance", DataType::FLOAT32, bytes(&[0.1f32]));
    }
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
    for o in [list, volume, field] {
        h.d.release(o);
    }

    // The tool's camera: on +z, fovy 60 degrees, the bounds' larger
    // in-plane half-size times 1.1 in view.
    let Some(Property::Box3(b)) = h.d.property(Subject::Object(world), "bounds", true) else {
        panic!("{backend} {case:?}: the world has no bounds");
    };
    let (lo, hi) = (Vec3::from_slice(&b[..3]), Vec3::from_slice(&b[3..]));
    let (size, centre) = (hi - lo, 0.5 * (lo + hi));
    let distance = 1.1 * 0.5 * size.x.max(size.y) / 0.5774 + 0.5 * size.z;
    let eye = centre + Vec3::new(0.0, 0.0, distance);
    let camera = h.d.new_object(DataType::CAMERA, "perspective");
    h.set(
        camera,
        "position",
        DataType::FLOAT32_VEC3,
        bytes(&eye.to_array()),
    );
    h.set(
        camera,
        "direction",
        DataType::FLOAT32_VEC3,
        bytes(&(centre - eye).normalize().to_array()),
    );
    h.set(
        camera,
        "up",
        DataType::FLOAT32_VEC3,
        bytes(&[0.0f32, 1.0, 0.0]),
    );
    h.set(camera, "aspect", DataType::FLOAT32, bytes(&[1.0f32]));
    h.d.commit(Subject::Object(camera));
    let renderer = h.d.new_object(DataType::RENDERER, "default");
    h.d.commit(Subject::Object(renderer));
    let frame = h.d.new_object(DataType::FRAME, "");
    h.set(frame, "size", DataType::UINT32_VEC2, bytes(&[SIZE, SIZE]));
    h.set(
        frame,
        "channel.color",
        DataType::DATA_TYPE,
        bytes(&[DataType::UFIXED8_RGBA_SRGB as i32]),
    );
    h.set(
        frame,
        "channel.depth",
        DataType::DATA_TYPE,
        bytes(&[DataType::FLOAT32 as i32]),
    );
    h.set_object(frame, "world", DataType::WORLD, world);
    h.set_object(frame, "camera", DataType::CAMERA, camera);
    h.set_object(frame, "renderer", DataType::RENDERER, renderer);
    h.d.commit(Subject::Object(frame));
    let color = h.pixels_sized(frame, SIZE, SIZE);
    let raw_depth = h.depth_sized(frame, SIZE, SIZE);
    let scale = 2.0 * size.length();
    let depth = raw_depth
        .iter()
        .flat_map(|&d| {
            let g = if d.is_finite() {
                (d / scale * 255.0).round().clamp(0.0, 255.0) as u8
            } else {
                255
            };
            [g, g, g, 255]
        })
        .collect();
    let said: Vec<String> = [Severity::Error, Severity::Warning]
        .into_iter()
        .flat_map(|s| h.messages(s))
        .collect();
    assert!(said.is_empty(), "{backend} {case:?}: {said:?}");
    for o in [frame, camera, renderer, world] {
        h.d.release(o);
    }
    Images {
        color,
        depth,
        raw_depth,
        eye,
    }
}

fn srgb_to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[test]
fn the_conformance_tools_volume_cases_pass_its_rule_gpu_against_cpu() {
    let n = (SIZE * SIZE) as usize;
    let w = SIZE as usize;
    for case in CASES {
        let cpu = render("cpu", case);
        let gpu = render("gpu", case);
        for (channel, a, b) in [
            ("color", &cpu.color, &gpu.color),
            ("depth", &cpu.depth, &gpu.depth),
        ] {
            let (s, p) = score(a, b, w, w);
            println!("{case:?} {channel}: SSIM {s:.4}, PSNR {p:.1} dB");
            assert!(
                s >= MIN_SSIM && p >= MIN_PSNR,
                "{case:?} {channel}: SSIM {s:.4}, PSNR {p:.1} dB (the tool asks {MIN_SSIM}, {MIN_PSNR} dB)"
            );
        }
        let covered = (0..n)
            .filter(|&i| cpu.raw_depth[i].is_finite() || cpu.color[4 * i..4 * i + 3] != [0, 0, 0])
            .count();
        assert!(
            covered > n / 4,
            "{case:?}: the volume covers {covered} of {n} pixels"
        );
        match case {
            // One color: every pixel is that color times the coverage, over
            // black: green is 0.75 red, blue none.
            Case::ColorVec3 | Case::ColorVec4 => {
                for i in 0..n {
                    let [r, g, b] = [0, 1, 2].map(|c| srgb_to_linear(cpu.color[4 * i + c]));
                    assert!(
                        b == 0.0 && (g - 0.75 * r).abs() <= 0.01,
                        "{case:?} pixel {i}: {r} {g} {b}"
                    );
                }
            }
            // Opaque everywhere: the first sample, half a step (1/6) past
            // where the centre ray enters the box's face at z = 1/3, stops it.
            Case::OpacityScalar => {
                let centre = (SIZE / 2 * SIZE + SIZE / 2) as usize;
                let entry = cpu.eye.z - 1.0 / 3.0;
                let d = cpu.raw_depth[centre];
                assert!(
                    (d - entry - 1.0 / 6.0).abs() < 0.02,
                    "depth {d}, entry {entry}"
                );
            }
            _ => {}
        }
    }
}

/// The score's two halves on images whose answer is known.
#[test]
fn the_score_follows_the_tools_formula() {
    let w = 16;
    let grey: Vec<u8> = (0..w * w)
        .flat_map(|i| [(i % 200) as u8, 100, 50, 255])
        .collect();
    assert_eq!(score(&grey, &grey, w, w), (1.0, f64::INFINITY));
    // Red 10 levels off everywhere: MSE 100 / 3 over the three channels.
    let off: Vec<u8> = grey
        .chunks_exact(4)
        .flat_map(|p| [p[0] + 10, p[1], p[2], p[3]])
        .collect();
    let (s, p) = score(&grey, &off, w, w);
    assert!(
        (p - 10.0 * (255.0f64 * 255.0 * 3.0 / 100.0).log10()).abs() < 1e-9,
        "{p}"
    );
    assert!(s > 0.9 && s < 1.0, "{s}");
    // Transparent pixels count as white: a clear image equals a white one.
    let clear = vec![0u8; 4 * w * w];
    let white = vec![255u8; 4 * w * w];
    assert_eq!(score(&clear, &white, w, w).0, 1.0);
    // Structure lost: a checker against flat grey scores far below the bar.
    let checker: Vec<u8> = (0..w * w)
        .flat_map(|i| {
            let v = if (i % w + i / w) % 2 == 0 { 0 } else { 255 };
            [v, v, v, 255]
        })
        .collect();
    let flat = vec![128u8; 4 * w * w];
    let (s, p) = score(&checker, &flat, w, w);
    assert!(s < MIN_SSIM && p < MIN_PSNR, "{s} {p}");
}
