//! What an accumulating host pays for rendering an unchanged frame again:
//! one full render of a CAVE-wall-sized frame, then the host's re-renders
//! (OpenCOVER renders an unchanged channel up to 64 times), each read back
//! through the frame's `duration` property, as a host reads it.
//!
//! `cargo run --release --example unchanged_frames [-- cpu|gpu|auto]`

use std::sync::Arc;

use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::device::{DataType, Device, Input, Property, Status, Subject};

fn bytes<T: Copy>(values: &[T]) -> Vec<u8> {
    // SAFETY: plain numbers, read as their bytes.
    unsafe {
        std::slice::from_raw_parts(values.as_ptr().cast::<u8>(), std::mem::size_of_val(values))
    }
    .to_vec()
}

fn main() {
    let backend = std::env::args().nth(1).unwrap_or_else(|| "auto".into());
    let mut d = Device::new(Arc::new(|s: Status| eprintln!("{}", s.message)));
    d.set_param(Subject::Device, "backend", Input::String(backend.clone()));
    d.commit(Subject::Device);
    let set = |d: &mut Device, o: u64, name: &str, ty: DataType, v: Vec<u8>| {
        d.set_param(Subject::Object(o), name, Input::Bytes(ty, v))
    };
    let link = |d: &mut Device, o: u64, name: &str, ty: DataType, h: u64| {
        d.set_param(Subject::Object(o), name, Input::Object(ty, h))
    };

    // The phantom at 128^3 and its preset, as `caveray render` shows it.
    let n = 128u64;
    let volume = shepp_logan(n as u32);
    let voxels: Vec<f32> = (0..volume.voxels().len())
        .map(|i| volume.value(i))
        .collect();
    let data = d
        .new_array(DataType::ARRAY3D, DataType::FLOAT32 as i32, [n, n, n], None)
        .ok()
        .expect("the voxels fit in memory");
    let ptr = d.map_array(data);
    // SAFETY: the device allocated n^3 FLOAT32 values.
    unsafe { std::ptr::copy_nonoverlapping(bytes(&voxels).as_ptr(), ptr, 4 * voxels.len()) };
    d.unmap_array(data);
    let field = d.new_object(DataType::SPATIAL_FIELD, "structuredRegular");
    link(&mut d, field, "data", DataType::ARRAY3D, data);
    set(
        &mut d,
        field,
        "origin",
        DataType::FLOAT32_VEC3,
        bytes(&[-1.0f32; 3]),
    );
    set(
        &mut d,
        field,
        "spacing",
        DataType::FLOAT32_VEC3,
        bytes(&[2.0 / (n - 1) as f32; 3]),
    );
    d.commit(Subject::Object(field));
    let tf = preset("phantom").expect("a shipped preset").table();
    let colors: Vec<f32> = tf.iter().flat_map(|c| [c.x, c.y, c.z]).collect();
    let opacities: Vec<f32> = tf.iter().map(|c| c.w).collect();
    let array = |d: &mut Device, ty: DataType, count: usize, v: &[f32]| {
        let a = d
            .new_array(DataType::ARRAY1D, ty as i32, [count as u64, 1, 1], None)
            .ok()
            .expect("a small array");
        let p = d.map_array(a);
        // SAFETY: the device allocated `count` elements of `ty`.
        unsafe { std::ptr::copy_nonoverlapping(bytes(v).as_ptr(), p, 4 * v.len()) };
        d.unmap_array(a);
        a
    };
    let color = array(&mut d, DataType::FLOAT32_VEC3, tf.len(), &colors);
    let opacity = array(&mut d, DataType::FLOAT32, tf.len(), &opacities);
    let vol = d.new_object(DataType::VOLUME, "transferFunction1D");
    link(&mut d, vol, "value", DataType::SPATIAL_FIELD, field);
    link(&mut d, vol, "color", DataType::ARRAY1D, color);
    link(&mut d, vol, "opacity", DataType::ARRAY1D, opacity);
    d.commit(Subject::Object(vol));
    let list = d
        .new_array(DataType::ARRAY1D, DataType::VOLUME as i32, [1, 1, 1], None)
        .ok()
        .expect("a small array");
    let p = d.map_array(list);
    // SAFETY: one handle.
    unsafe { std::ptr::copy_nonoverlapping(bytes(&[vol as usize]).as_ptr(), p, 8) };
    d.unmap_array(list);
    let world = d.new_object(DataType::WORLD, "");
    link(&mut d, world, "volume", DataType::ARRAY1D, list);
    d.commit(Subject::Object(world));
    let renderer = d.new_object(DataType::RENDERER, "default");
    d.set_param(
        Subject::Object(renderer),
        "shading",
        Input::String("shadows".into()),
    );
    d.commit(Subject::Object(renderer));
    let camera = d.new_object(DataType::CAMERA, "perspective");
    set(
        &mut d,
        camera,
        "position",
        DataType::FLOAT32_VEC3,
        bytes(&[0.0f32, 0.0, 3.0]),
    );
    d.commit(Subject::Object(camera));
    let frame = d.new_object(DataType::FRAME, "");
    set(
        &mut d,
        frame,
        "size",
        DataType::UINT32_VEC2,
        bytes(&[512u32, 512]),
    );
    set(
        &mut d,
        frame,
        "channel.color",
        DataType::DATA_TYPE,
        bytes(&[DataType::UFIXED8_RGBA_SRGB as i32]),
    );
    link(&mut d, frame, "world", DataType::WORLD, world);
    link(&mut d, frame, "renderer", DataType::RENDERER, renderer);
    link(&mut d, frame, "camera", DataType::CAMERA, camera);
    d.commit(Subject::Object(frame));

    // (duration the device reports, wall time the host waits), in ms.
    let render = |d: &mut Device| -> (f64, f64) {
        let t = std::time::Instant::now();
        d.render_frame(frame, None);
        let duration = match d.property(Subject::Object(frame), "duration", true) {
            Some(Property::Float32(s)) => f64::from(s) * 1e3,
            _ => f64::NAN,
        };
        (duration, t.elapsed().as_secs_f64() * 1e3)
    };
    let (full, full_wall) = render(&mut d);
    let again: Vec<(f64, f64)> = (0..64).map(|_| render(&mut d)).collect();
    let mean = |f: fn(&(f64, f64)) -> f64| again.iter().map(f).sum::<f64>() / again.len() as f64;
    println!("backend {backend}, 512x512 sRGB, phantom 128^3 with shadows");
    println!("  full render:              duration {full:9.1} ms, host waits {full_wall:9.1} ms");
    println!(
        "  64 unchanged re-renders:  duration {:9.4} ms, host waits {:9.4} ms (means)",
        mean(|r| r.0),
        mean(|r| r.1)
    );
}
