//! A CAVE plug-in's view of caveray: dlopen the built library at run time
//! (libloading), look up the C entry points by name, and render a wall
//! through the C ABI alone; the image must match the Rust API's.

use crate::common;

use std::ffi::{c_char, c_void, CStr};
use std::sync::atomic::{AtomicUsize, Ordering};

use anari_library_caveray::capi::sys::*;
use anari_library_caveray::render::ssim;
use common::c::{lib_dir, phantom, read_rgba, scratch, wall_scene};

static PROBLEMS: AtomicUsize = AtomicUsize::new(0);

unsafe extern "C" fn on_status(
    _user: *const c_void,
    _device: ANARIDevice,
    _source: ANARIObject,
    _source_type: ANARIDataType,
    severity: ANARIStatusSeverity,
    _code: ANARIStatusCode,
    message: *const c_char,
) {
    if severity <= ANARI_SEVERITY_WARNING {
        PROBLEMS.fetch_add(1, Ordering::SeqCst);
        eprintln!("status: {}", CStr::from_ptr(message).to_string_lossy());
    }
}

/// Reads the test scene file's numbers back (the Rust side wrote it).
fn numbers(text: &str, key: &str) -> Vec<f32> {
    let line = text
        .lines()
        .find(|l| l.split_whitespace().next() == Some(key))
        .unwrap();
    line.split_whitespace()
        .skip(1)
        .filter_map(|w| w.parse().ok())
        .collect()
}

// The entry points keep their C names, as a plug-in host would write them.
#[allow(non_snake_case)]
#[test]
fn dlopened_library_renders_a_wall_through_the_c_abi() {
    let dir = scratch("capi_dlopen");
    let scene = wall_scene(&dir, 64, phantom(), false);
    let text = std::fs::read_to_string(&scene.file).unwrap();
    let raw = text
        .lines()
        .next()
        .unwrap()
        .split_whitespace()
        .nth(4)
        .unwrap();
    let voxels: Vec<f32> = std::fs::read(raw)
        .unwrap()
        .chunks_exact(4)
        .map(|c| f32::from_ne_bytes(c.try_into().unwrap()))
        .collect();
    let dims = numbers(&text, "dims");
    let colors = numbers(&text, "rgba");
    let opacities = numbers(&text, "alpha");

    let lib = unsafe { libloading::Library::new(lib_dir().join("libanari_library_caveray.so")) }
        .expect("the built library loads");
    macro_rules! sym {
        ($name:ident : $ty:ty) => {
            let $name: libloading::Symbol<$ty> =
                unsafe { lib.get(concat!(stringify!($name), "\0").as_bytes()) }
                    .expect(stringify!($name));
        };
    }
    sym!(anariLoadLibrary: unsafe extern "C" fn(*const c_char, ANARIStatusCallback, *const c_void) -> ANARILibrary);
    sym!(anariUnloadLibrary: unsafe extern "C" fn(ANARILibrary));
    sym!(anariNewDevice: unsafe extern "C" fn(ANARILibrary, *const c_char) -> ANARIDevice);
    sym!(anariNewArray1D: unsafe extern "C" fn(ANARIDevice, *const c_void, ANARIMemoryDeleter, *const c_void, ANARIDataType, u64) -> ANARIArray1D);
    sym!(anariNewArray3D: unsafe extern "C" fn(ANARIDevice, *const c_void, ANARIMemoryDeleter, *const c_void, ANARIDataType, u64, u64, u64) -> ANARIArray3D);
    sym!(anariNewObject: unsafe extern "C" fn(ANARIDevice, *const c_char, *const c_char) -> ANARIObject);
    sym!(anariSetParameter: unsafe extern "C" fn(ANARIDevice, ANARIObject, *const c_char, ANARIDataType, *const c_void));
    sym!(anariCommitParameters: unsafe extern "C" fn(ANARIDevice, ANARIObject));
    sym!(anariRelease: unsafe extern "C" fn(ANARIDevice, ANARIObject));
    sym!(anariRenderFrame: unsafe extern "C" fn(ANARIDevice, ANARIFrame));
    sym!(anariFrameReady: unsafe extern "C" fn(ANARIDevice, ANARIFrame, ANARIWaitMask) -> i32);
    sym!(anariMapFrame: unsafe extern "C" fn(ANARIDevice, ANARIFrame, *const c_char, *mut u32, *mut u32, *mut ANARIDataType) -> *const c_void);
    sym!(anariUnmapFrame: unsafe extern "C" fn(ANARIDevice, ANARIFrame, *const c_char));

    let c = |s: &str| std::ffi::CString::new(s).unwrap();
    unsafe {
        let library = anariLoadLibrary(c("caveray").as_ptr(), Some(on_status), std::ptr::null());
        let dev = anariNewDevice(library, c("default").as_ptr());
        assert!(!dev.is_null());
        let new = |kind: &str, sub: &str| anariNewObject(dev, c(kind).as_ptr(), c(sub).as_ptr());
        let set = |o: ANARIObject, name: &str, ty: i32, v: *const c_void| {
            anariSetParameter(dev, o, c(name).as_ptr(), ty, v)
        };

        let data = anariNewArray3D(
            dev,
            voxels.as_ptr().cast(),
            None,
            std::ptr::null(),
            ANARI_FLOAT32,
            dims[0] as u64,
            dims[1] as u64,
            dims[2] as u64,
        );
        let field = new("spatialField", "structuredRegular");
        set(
            field,
            "data",
            ANARI_ARRAY3D,
            (&data as *const ANARIArray3D).cast(),
        );
        set(
            field,
            "origin",
            ANARI_FLOAT32_VEC3,
            numbers(&text, "origin").as_ptr().cast(),
        );
        set(
            field,
            "spacing",
            ANARI_FLOAT32_VEC3,
            numbers(&text, "spacing").as_ptr().cast(),
        );
        anariCommitParameters(dev, field);

        let color = anariNewArray1D(
            dev,
            colors.as_ptr().cast(),
            None,
            std::ptr::null(),
            ANARI_FLOAT32_VEC4,
            colors.len() as u64 / 4,
        );
        let opacity = anariNewArray1D(
            dev,
            opacities.as_ptr().cast(),
            None,
            std::ptr::null(),
            ANARI_FLOAT32,
            opacities.len() as u64,
        );
        let volume = new("volume", "transferFunction1D");
        set(
            volume,
            "value",
            ANARI_SPATIAL_FIELD,
            (&field as *const ANARIObject).cast(),
        );
        set(
            volume,
            "color",
            ANARI_ARRAY1D,
            (&color as *const ANARIArray1D).cast(),
        );
        set(
            volume,
            "opacity",
            ANARI_ARRAY1D,
            (&opacity as *const ANARIArray1D).cast(),
        );
        set(
            volume,
            "valueRange",
            ANARI_FLOAT32_BOX1,
            numbers(&text, "range").as_ptr().cast(),
        );
        set(
            volume,
            "unitDistance",
            ANARI_FLOAT32,
            numbers(&text, "unit").as_ptr().cast(),
        );
        anariCommitParameters(dev, volume);

        let volumes = anariNewArray1D(
            dev,
            (&volume as *const ANARIObject).cast(),
            None,
            std::ptr::null(),
            ANARI_VOLUME,
            1,
        );
        let world = new("world", "");
        set(
            world,
            "volume",
            ANARI_ARRAY1D,
            (&volumes as *const ANARIArray1D).cast(),
        );
        anariCommitParameters(dev, world);
        let renderer = new("renderer", "default");
        anariCommitParameters(dev, renderer);

        let camera = new("camera", "offAxis");
        for (name, key) in [
            ("lowerLeft", "ll"),
            ("lowerRight", "lr"),
            ("upperRight", "ur"),
            ("eye", "eye"),
        ] {
            set(
                camera,
                name,
                ANARI_FLOAT32_VEC3,
                numbers(&text, key).as_ptr().cast(),
            );
        }
        anariCommitParameters(dev, camera);

        let frame = new("frame", "");
        let size = [scene.size.x, scene.size.y];
        let rgba8 = ANARI_UFIXED8_VEC4;
        set(frame, "size", ANARI_UINT32_VEC2, size.as_ptr().cast());
        set(
            frame,
            "channel.color",
            ANARI_DATA_TYPE,
            (&rgba8 as *const i32).cast(),
        );
        for (name, ty, o) in [
            ("world", ANARI_WORLD, world),
            ("renderer", ANARI_RENDERER, renderer),
            ("camera", ANARI_CAMERA, camera),
        ] {
            set(frame, name, ty, (&o as *const ANARIObject).cast());
        }
        anariCommitParameters(dev, frame);
        anariRenderFrame(dev, frame);
        assert_eq!(anariFrameReady(dev, frame, ANARI_WAIT as u32), 1);
        let (mut w, mut h, mut ty) = (0u32, 0u32, 0);
        let channel = c("channel.color");
        let pixels = anariMapFrame(dev, frame, channel.as_ptr(), &mut w, &mut h, &mut ty);
        assert!(!pixels.is_null());
        assert_eq!((w, h, ty), (size[0], size[1], ANARI_UFIXED8_VEC4));
        let bytes = std::slice::from_raw_parts(pixels.cast::<u8>(), (4 * w * h) as usize).to_vec();
        anariUnmapFrame(dev, frame, channel.as_ptr());

        for o in [
            frame, camera, renderer, world, volumes, volume, opacity, color, field, data, dev,
        ] {
            anariRelease(dev, o);
        }
        anariUnloadLibrary(library);

        let path = dir.join("dlopen.rgba");
        std::fs::write(&path, bytes).unwrap();
        let image = read_rgba(&path, scene.size);
        let s = ssim(&image, &scene.reference).unwrap();
        assert!(
            s > 0.98,
            "offAxis camera through the dlopened C ABI: SSIM {s:.4}"
        );
    }
    assert_eq!(
        PROBLEMS.load(Ordering::SeqCst),
        0,
        "errors or warnings were reported"
    );
}
