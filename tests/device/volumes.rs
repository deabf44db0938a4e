//! Volumes as hosts build them, through the device model on the CPU
//! reference: the value range as a VEC2 or collapsed to one value, color
//! arrays of every element type, out-of-range maps, the legacy `field`
//! name and the `filter` values.

use crate::common;

use anari_library_caveray::device::{DataType, Severity};
use common::device::{bytes, centre, same, Host};

#[test]
fn value_range_as_a_vec2_equals_the_box1() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let mut image = |ty| {
        let v = h.volume(field);
        h.set(v, "valueRange", ty, bytes(&[0.0f32, 1.0]));
        h.set(v, "opacity", DataType::FLOAT32, bytes(&[0.5f32]));
        h.render(v)
    };
    let boxed = image(DataType::FLOAT32_BOX1);
    let vec2 = image(DataType::FLOAT32_VEC2);
    same(&boxed, &vec2).unwrap();
    assert!(centre(&boxed)[0] > 50, "{:?}", centre(&boxed));
    assert!(h.messages(Severity::Error).is_empty());
}

#[test]
fn a_constant_field_takes_the_middle_of_the_maps() {
    let mut h = Host::new();
    let field = h.field(|_| 7.0, None);
    let v = h.volume(field);
    h.set(
        v,
        "valueRange",
        DataType::FLOAT32_BOX1,
        bytes(&[7.0f32, 7.0]),
    );
    let colors = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32_VEC3,
        [3, 1, 1],
        &bytes(&[1.0f32, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]),
    );
    h.set_object(v, "color", DataType::ARRAY1D, colors);
    h.set(v, "opacity", DataType::FLOAT32, bytes(&[1.0f32]));
    let image = h.render(v);
    assert!(h.messages(Severity::Error).is_empty());
    let [r, g, b] = centre(&image);
    assert!(
        g > 200 && r < 10 && b < 10,
        "the middle color is green, got {r} {g} {b}"
    );
}

#[test]
fn color_arrays_of_every_element_type_read_alike() {
    // Red, then white at full alpha: exact in every encoding.
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let mut image = |ty: DataType, data: Vec<u8>| {
        let v = h.volume(field);
        let a = h.array(DataType::ARRAY1D, ty, [2, 1, 1], &data);
        h.set_object(v, "color", DataType::ARRAY1D, a);
        h.set(v, "opacity", DataType::FLOAT32, bytes(&[0.6f32]));
        h.d.release(a);
        let img = h.render(v);
        let errors = h.messages(Severity::Error);
        assert!(errors.is_empty(), "{ty}: {errors:?}");
        img
    };
    let reference = image(
        DataType::FLOAT32_VEC4,
        bytes(&[1.0f32, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0]),
    );
    let alike = [
        (
            DataType::FLOAT32_VEC3,
            bytes(&[1.0f32, 0.0, 0.0, 1.0, 1.0, 1.0]),
        ),
        (
            DataType::UFIXED8_VEC4,
            vec![255, 0, 0, 255, 255, 255, 255, 255],
        ),
        (DataType::UFIXED8_VEC3, vec![255, 0, 0, 255, 255, 255]),
        (
            DataType::UFIXED16_VEC4,
            bytes(&[65535u16, 0, 0, 65535, 65535, 65535, 65535, 65535]),
        ),
        (
            DataType::UFIXED16_VEC3,
            bytes(&[65535u16, 0, 0, 65535, 65535, 65535]),
        ),
        (
            DataType::UFIXED8_RGBA_SRGB,
            vec![255, 0, 0, 255, 255, 255, 255, 255],
        ),
        (DataType::UFIXED8_RGB_SRGB, vec![255, 0, 0, 255, 255, 255]),
    ];
    for (ty, data) in alike {
        same(&image(ty, data), &reference).unwrap_or_else(|e| panic!("{ty}: {e}"));
    }
    // Fewer components: the missing color reads 0 and alpha 1.
    let red_only = image(DataType::FLOAT32, bytes(&[1.0f32, 1.0]));
    let [r, g, b] = centre(&red_only);
    assert!(
        r > 50 && g == 0 && b == 0,
        "one component is red: {r} {g} {b}"
    );
    same(&image(DataType::UFIXED8, vec![255, 255]), &red_only).unwrap();
    same(&image(DataType::UFIXED8_R_SRGB, vec![255, 255]), &red_only).unwrap();
    // sRGB is decoded: 188 is about 0.5 linear, 128 would be 0.216.
    let srgb = image(
        DataType::UFIXED8_RGBA_SRGB,
        vec![188, 188, 188, 255, 188, 188, 188, 255],
    );
    let linear = image(
        DataType::FLOAT32_VEC4,
        bytes(&[0.5f32, 0.5, 0.5, 1.0, 0.5, 0.5, 0.5, 1.0]),
    );
    let d = centre(&srgb)[0].abs_diff(centre(&linear)[0]);
    assert!(
        d <= 2,
        "sRGB 188 reads {} against linear 0.5's {}",
        centre(&srgb)[0],
        centre(&linear)[0]
    );
}

#[test]
fn out_of_range_maps_are_clamped_with_a_warning() {
    fn image(h: &mut Host, field: u64, rgb: [f32; 3], opacity: f32) -> Vec<u8> {
        let v = h.volume(field);
        h.set(v, "color", DataType::FLOAT32_VEC3, bytes(&rgb));
        let o = h.array(
            DataType::ARRAY1D,
            DataType::FLOAT32,
            [1, 1, 1],
            &bytes(&[opacity]),
        );
        h.set_object(v, "opacity", DataType::ARRAY1D, o);
        h.d.release(o);
        h.render(v)
    }
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let clamped = image(&mut h, field, [1.5, -0.5, 0.5], 2.0);
    let warnings = h.messages(Severity::Warning);
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("2 color components lie outside [0, 1]") && w.contains("clamped"))
            && warnings
                .iter()
                .any(|w| w.contains("1 opacities lie outside [0, 1]")
                    && w.contains("opacity[0] = 2")),
        "{warnings:?}"
    );
    assert!(h.messages(Severity::Error).is_empty());
    same(&clamped, &image(&mut h, field, [1.0, 0.0, 0.5], 1.0)).unwrap();
}

#[test]
fn the_legacy_field_name_and_every_filter_value() {
    let mut h = Host::new();
    // A faint ramp, so how the field is sampled shows in the image.
    let faint = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32,
        [2, 1, 1],
        &bytes(&[0.0f32, 0.2]),
    );
    let ramp = |x: u32| x as f32 / 3.0;
    let image = |h: &mut Host, filter: Option<&str>, name: &str| {
        let f = h.field(ramp, filter);
        let v = h.d.new_object(DataType::VOLUME, "transferFunction1D");
        h.set_object(v, name, DataType::SPATIAL_FIELD, f);
        h.set_object(v, "opacity", DataType::ARRAY1D, faint);
        h.render(v)
    };
    let by_value = image(&mut h, None, "value");
    let by_field = image(&mut h, None, "field");
    same(&by_value, &by_field).unwrap();
    assert!(h.messages(Severity::Error).is_empty());

    let linear = image(&mut h, Some("linear"), "value");
    same(&linear, &by_value).unwrap();
    let cubic = image(&mut h, Some("cubic"), "value");
    let warnings = h.messages(Severity::Warning);
    assert!(
        warnings.iter().any(|w| w.contains("filter 'cubic' is not one of linear, nearest; sampling is linear")),
        "{warnings:?}"
    );
    same(&cubic, &linear).unwrap();
    let nearest = image(&mut h, Some("nearest"), "value");
    assert!(h.messages(Severity::Warning).is_empty());
    assert!(
        same(&nearest, &linear).is_err(),
        "nearest rendered as linear"
    );
}

/// A colour array with alpha and no opacity array: the alphas are the
/// opacities, as the other ANARI devices read it (pynari's samples send
/// their maps so), on both renderers.
#[test]
fn a_color_alpha_without_an_opacity_array_is_the_opacity() {
    for backend in ["cpu", "gpu"] {
        let mut h = Host::on_backend(backend, std::sync::Arc::new(|_| {}));
        let field = h.field(|x| x as f32 / 3.0, None);
        let mut image = |colors: &[f32], opacity: Option<f32>| {
            let v = h.volume(field);
            let a = h.array(
                DataType::ARRAY1D,
                DataType::FLOAT32_VEC4,
                [2, 1, 1],
                &bytes(colors),
            );
            h.set_object(v, "color", DataType::ARRAY1D, a);
            if let Some(o) = opacity {
                h.set(v, "opacity", DataType::FLOAT32, bytes(&[o]));
            }
            h.d.release(a);
            let img = h.render(v);
            let errors = h.messages(Severity::Error);
            assert!(errors.is_empty(), "{backend}: {errors:?}");
            img
        };
        let from_alpha = image(&[0.2, 0.4, 1.0, 0.3, 1.0, 0.5, 0.0, 0.3], None);
        let from_opacity = image(&[0.2, 0.4, 1.0, 1.0, 1.0, 0.5, 0.0, 1.0], Some(0.3));
        same(&from_alpha, &from_opacity).unwrap_or_else(|e| panic!("{backend}: {e}"));
        let opaque = image(&[0.2, 0.4, 1.0, 1.0, 1.0, 0.5, 0.0, 1.0], None);
        assert_ne!(from_alpha, opaque, "{backend}: the alpha changed nothing");
    }
}

#[test]
fn a_gpu_memory_budget_too_small_for_a_brick_is_refused_and_residency_is_reported() {
    use anari_library_caveray::device::{Input, Property, Status, Subject};
    use std::sync::{Arc, Mutex};
    let said = Arc::new(Mutex::new(Vec::<Status>::new()));
    let sink = Arc::clone(&said);
    let mut h = Host::on_backend(
        "gpu",
        Arc::new(move |s: Status| sink.lock().unwrap().push(s)),
    );
    // 4^3 float32 voxels: 256 bytes in host memory, 256 as a texture.
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    let bytes_of = |h: &mut Host, object: u64, name: &str| match h.d.property(
        Subject::Object(object),
        name,
        true,
    ) {
        Some(Property::UInt64(n)) => n,
        other => panic!("{name}: {other:?}"),
    };
    assert_eq!(bytes_of(&mut h, field, "caveray.residentBytes"), 256);
    let budget = |h: &mut Host, bytes: u64| {
        h.d.set_param(
            Subject::Device,
            "caveray.memoryBudget",
            Input::Bytes(DataType::UINT64, bytes.to_le_bytes().to_vec()),
        );
        h.d.commit(Subject::Device);
    };
    budget(&mut h, 255);
    let (frame, _camera) = h.frame(volume, 3.0);
    h.d.render_frame(frame, None);
    assert!(h.d.map_frame(frame, "channel.color").is_none());
    let errors: Vec<String> = said
        .lock()
        .unwrap()
        .iter()
        .filter(|s| s.severity == Severity::Error)
        .map(|s| s.message.clone())
        .collect();
    // Past the budget the world's volume would be paged, but its pool
    // would not hold its one brick.
    assert!(
        errors
            .iter()
            .any(|e| e.contains("cannot allocate 256 bytes for one 4x4x4 brick of a 4x4x4 volume, past its share of the GPU memory budget of 255 bytes")),
        "{errors:?}"
    );
    // Within the budget (and with none), the frame renders and says what
    // its volume holds: the voxels, and their texture on the GPU.
    for bytes in [256, 0] {
        budget(&mut h, bytes);
        h.pixels(frame);
        assert_eq!(bytes_of(&mut h, frame, "caveray.gpuBytes"), 256);
        assert_eq!(bytes_of(&mut h, frame, "caveray.residentBytes"), 512);
    }
    assert_eq!(bytes_of(&mut h, volume, "caveray.residentBytes"), 256);
}

/// A fresh GPU device with a 200 x 200 x 8 float32 field (1.28 MB:
/// bricks of 63 x 63 x 8 voxels, 128 KiB each in the pool, 16 at full
/// detail and 21 in the chain) under a memory budget of `budget` bytes,
/// its frames waiting `wait` ms for bricks where set: the host and the
/// frame.
fn paged_world(budget: u64, wait: Option<f32>) -> (Host, u64) {
    use anari_library_caveray::device::{Input, Subject};
    let mut h = Host::on_backend("gpu", std::sync::Arc::new(|_| {}));
    let (nx, ny, nz) = (200u32, 200u32, 8u32);
    let voxels: Vec<f32> = (0..nx * ny * nz)
        .map(|i| {
            let x = (i % nx) as f32 / nx as f32;
            let y = (i / nx % ny) as f32 / ny as f32;
            ((x * 9.0).sin() * (y * 7.0).cos()).abs()
        })
        .collect();
    let data = h.array(
        DataType::ARRAY3D,
        DataType::FLOAT32,
        [nx.into(), ny.into(), nz.into()],
        &bytes(&voxels),
    );
    let field = h.d.new_object(DataType::SPATIAL_FIELD, "structuredRegular");
    h.set_object(field, "data", DataType::ARRAY3D, data);
    h.set(
        field,
        "origin",
        DataType::FLOAT32_VEC3,
        bytes(&[-1.0f32, -1.0, -0.04]),
    );
    h.set(
        field,
        "spacing",
        DataType::FLOAT32_VEC3,
        bytes(&[0.01f32; 3]),
    );
    h.d.commit(Subject::Object(field));
    h.d.release(data);
    let volume = h.volume(field);
    h.d.set_param(
        Subject::Device,
        "caveray.memoryBudget",
        Input::Bytes(DataType::UINT64, budget.to_le_bytes().to_vec()),
    );
    if let Some(ms) = wait {
        h.d.set_param(
            Subject::Device,
            "caveray.streamWait",
            Input::Bytes(DataType::FLOAT32, bytes(&[ms])),
        );
    }
    h.d.commit(Subject::Device);
    let (frame, _camera) = h.frame(volume, 3.0);
    (h, frame)
}

fn render_progress(h: &mut Host, frame: u64) -> f32 {
    use anari_library_caveray::device::{Property, Subject};
    match h.d.property(Subject::Object(frame), "renderProgress", true) {
        Some(Property::Float32(p)) => p,
        other => panic!("renderProgress: {other:?}"),
    }
}

/// A world past the GPU memory budget is paged within it; with
/// `caveray.streamWait` set, frames render what is resident and say how
/// much through `renderProgress`, and rendering again refines the image
/// until it equals the frame that waited for every brick.
#[test]
fn a_world_past_the_gpu_budget_streams_and_render_progress_reaches_one() {
    use anari_library_caveray::device::{Property, Subject};
    let budget = 1_200_000;
    let (mut h, frame) = paged_world(budget, None);
    let complete = h.pixels(frame);
    assert_eq!(
        render_progress(&mut h, frame),
        1.0,
        "a frame that waits has every brick"
    );
    let gpu = match h
        .d
        .property(Subject::Object(frame), "caveray.gpuBytes", true)
    {
        Some(Property::UInt64(n)) => n,
        other => panic!("caveray.gpuBytes: {other:?}"),
    };
    assert!(gpu <= budget, "{gpu} bytes on the GPU");
    assert!(h.messages(Severity::Error).is_empty());

    let (mut h, frame) = paged_world(budget, Some(0.0));
    let mut seen = Vec::new();
    let image = loop {
        let image = h.pixels(frame);
        let p = render_progress(&mut h, frame);
        assert!(p > 0.0 && p <= 1.0, "{p}");
        seen.push(p);
        if p >= 1.0 || seen.len() >= 500 {
            break image;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    println!("renderProgress over {} renders: {seen:?}", seen.len());
    assert_eq!(seen.last(), Some(&1.0), "{seen:?}");
    same(&image, &complete).unwrap();
    assert!(h.messages(Severity::Error).is_empty());

    // A wait that is not a duration is refused, and frames wait.
    let (mut h, _) = paged_world(budget, Some(-1.0));
    let errors = h.messages(Severity::Error);
    assert!(
        errors
            .iter()
            .any(|e| e
                .contains("'caveray.streamWait' must be one FLOAT32 of at least 0 milliseconds")),
        "{errors:?}"
    );
}
