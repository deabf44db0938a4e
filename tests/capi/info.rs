//! Introspection as hosts use it to build settings UIs and place cameras:
//! extension names, frame channels, parameter lists with every accepted
//! type, parameter info (element types, enumerations, ranges, source
//! extension), and the device and world properties, through the C entry
//! points.

use std::ffi::{c_char, c_void, CStr, CString};

use anari_library_caveray::capi::entry_points as api;
use anari_library_caveray::capi::sys::*;

fn c(s: &str) -> CString {
    CString::new(s).unwrap()
}

/// A NULL-terminated string list as Strings.
unsafe fn strings(list: *const *const c_char) -> Vec<String> {
    assert!(!list.is_null());
    let mut out = Vec::new();
    let mut p = list;
    while !(*p).is_null() {
        out.push(CStr::from_ptr(*p).to_string_lossy().into_owned());
        p = p.add(1);
    }
    out
}

/// A DATA_TYPE_LIST (ended by ANARI_UNKNOWN).
unsafe fn types(list: *const c_void) -> Vec<i32> {
    assert!(!list.is_null());
    let mut out = Vec::new();
    let mut p = list.cast::<i32>();
    while *p != ANARI_UNKNOWN {
        out.push(*p);
        p = p.add(1);
    }
    out
}

struct Session {
    lib: ANARILibrary,
    dev: ANARIDevice,
}

impl Session {
    fn new() -> Self {
        unsafe {
            let lib = api::anariLoadLibrary(c("caveray").as_ptr(), None, std::ptr::null());
            let dev = api::anariNewDevice(lib, c("default").as_ptr());
            assert!(!dev.is_null());
            Self { lib, dev }
        }
    }

    fn param_info(
        &self,
        kind: i32,
        sub: &str,
        param: &str,
        ty: i32,
        info: &str,
        info_ty: i32,
    ) -> *const c_void {
        unsafe {
            api::anariGetParameterInfo(
                self.dev,
                kind,
                c(sub).as_ptr(),
                c(param).as_ptr(),
                ty,
                c(info).as_ptr(),
                info_ty,
            )
        }
    }

    fn property<T: Copy + Default>(&self, obj: ANARIObject, name: &str, ty: i32) -> Option<T> {
        let mut value = T::default();
        let found = unsafe {
            api::anariGetProperty(
                self.dev,
                obj,
                c(name).as_ptr(),
                ty,
                (&mut value as *mut T).cast(),
                std::mem::size_of::<T>() as u64,
                ANARI_WAIT as ANARIWaitMask,
            )
        };
        (found == 1).then_some(value)
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        unsafe {
            api::anariRelease(self.dev, self.dev);
            api::anariUnloadLibrary(self.lib);
        }
    }
}

#[test]
fn extensions_carry_the_anari_prefix_and_name_what_is_implemented() {
    let s = Session::new();
    let names = unsafe { strings(api::anariGetDeviceExtensions(s.lib, c("default").as_ptr())) };
    assert!(names.iter().all(|n| n.starts_with("ANARI_")), "{names:?}");
    for expected in [
        "ANARI_KHR_CAMERA_PERSPECTIVE",
        "ANARI_KHR_SPATIAL_FIELD_STRUCTURED_REGULAR",
        "ANARI_KHR_VOLUME_TRANSFER_FUNCTION1D",
        "ANARI_KHR_FRAME_COMPLETION_CALLBACK",
        "ANARI_KHR_FRAME_ACCUMULATION",
        "ANARI_KHR_RENDERER_BACKGROUND_COLOR",
        "ANARI_VSNRAY_CAMERA_MATRIX",
        "ANARI_CAVERAY_CAMERA_MATRIX",
        "ANARI_CAVERAY_CAMERA_OFF_AXIS",
    ] {
        assert!(
            names.iter().any(|n| n == expected),
            "{expected} missing from {names:?}"
        );
    }
    // Every extension name caveray.h gives hosts is one the device reports.
    for header in [
        CAVERAY_EXTENSION_CAMERA_MATRIX_VSNRAY.as_slice(),
        CAVERAY_EXTENSION_CAMERA_MATRIX,
        CAVERAY_EXTENSION_CAMERA_OFF_AXIS,
        CAVERAY_EXTENSION_RENDERER_SHADING,
        CAVERAY_EXTENSION_FRAME_STEREO_PAIR,
    ] {
        let name = CStr::from_bytes_with_nul(header).unwrap().to_str().unwrap();
        assert!(
            names.iter().any(|n| n == name),
            "{name} missing from {names:?}"
        );
    }
    let property: Option<usize> = s.property(s.dev.cast(), "extension", ANARI_STRING_LIST);
    let listed = unsafe { strings(property.unwrap() as *const *const c_char) };
    assert_eq!(listed, names);
}

#[test]
fn frame_channels_and_parameters_listed_once_per_type() {
    let s = Session::new();
    let channels = unsafe {
        api::anariGetObjectInfo(
            s.dev,
            ANARI_FRAME,
            std::ptr::null(),
            c("channel").as_ptr(),
            ANARI_STRING_LIST,
        )
    };
    assert_eq!(
        unsafe { strings(channels.cast()) },
        [
            "channel.color",
            "channel.depth",
            "channel.primitiveId",
            "channel.objectId",
            "channel.instanceId",
            "channel.normal",
            "channel.albedo"
        ]
    );

    let list = unsafe {
        api::anariGetObjectInfo(
            s.dev,
            ANARI_VOLUME,
            c("transferFunction1D").as_ptr(),
            c("parameter").as_ptr(),
            ANARI_PARAMETER_LIST,
        )
    }
    .cast::<ANARIParameter>();
    let mut params = Vec::new();
    let mut p = list;
    unsafe {
        while !(*p).name.is_null() {
            params.push((
                CStr::from_ptr((*p).name).to_str().unwrap().to_owned(),
                (*p).type_,
            ));
            p = p.add(1);
        }
    }
    let color: Vec<i32> = params
        .iter()
        .filter(|(n, _)| n == "color")
        .map(|(_, t)| *t)
        .collect();
    assert_eq!(
        color,
        [ANARI_ARRAY1D, ANARI_FLOAT32_VEC3, ANARI_FLOAT32_VEC4]
    );
    let range: Vec<i32> = params
        .iter()
        .filter(|(n, _)| n == "valueRange")
        .map(|(_, t)| *t)
        .collect();
    assert_eq!(
        range,
        [ANARI_FLOAT32_BOX1, ANARI_FLOAT64_BOX1, ANARI_FLOAT32_VEC2]
    );
}

#[test]
fn parameter_info_answers_what_settings_uis_ask() {
    let s = Session::new();
    let elements = s.param_info(
        ANARI_SPATIAL_FIELD,
        "structuredRegular",
        "data",
        ANARI_ARRAY3D,
        "elementType",
        ANARI_DATA_TYPE_LIST,
    );
    let elements = unsafe { types(elements) };
    assert!(
        elements.contains(&ANARI_FLOAT32) && elements.contains(&ANARI_UFIXED8),
        "{elements:?}"
    );
    let colors = s.param_info(
        ANARI_VOLUME,
        "transferFunction1D",
        "color",
        ANARI_ARRAY1D,
        "elementType",
        ANARI_DATA_TYPE_LIST,
    );
    assert!(unsafe { types(colors) }.contains(&ANARI_UFIXED8_RGBA_SRGB));

    let filters = s.param_info(
        ANARI_SPATIAL_FIELD,
        "structuredRegular",
        "filter",
        ANARI_STRING,
        "value",
        ANARI_STRING_LIST,
    );
    assert_eq!(unsafe { strings(filters.cast()) }, ["linear", "nearest"]);
    let formats = s.param_info(
        ANARI_FRAME,
        "",
        "channel.color",
        ANARI_DATA_TYPE,
        "value",
        ANARI_DATA_TYPE_LIST,
    );
    assert_eq!(
        unsafe { types(formats) },
        [
            ANARI_UFIXED8_VEC4,
            ANARI_UFIXED8_RGBA_SRGB,
            ANARI_FLOAT32_VEC4
        ]
    );

    let lo = s.param_info(
        ANARI_RENDERER,
        "default",
        "stepFactor",
        ANARI_FLOAT32,
        "minimum",
        ANARI_FLOAT32,
    );
    let hi = s.param_info(
        ANARI_RENDERER,
        "default",
        "stepFactor",
        ANARI_FLOAT32,
        "maximum",
        ANARI_FLOAT32,
    );
    let (lo, hi) = unsafe { (*lo.cast::<f32>(), *hi.cast::<f32>()) };
    assert!(
        lo > 0.0 && lo < 1.0 && hi > 1.0,
        "stepFactor range {lo}..{hi}"
    );
    // A length in the host's own units: a minimum, and no maximum.
    let ipd = |info| {
        s.param_info(
            ANARI_CAMERA,
            "perspective",
            "interpupillaryDistance",
            ANARI_FLOAT32,
            info,
            ANARI_FLOAT32,
        )
    };
    assert_eq!(unsafe { *ipd("minimum").cast::<f32>() }, 0.0);
    assert!(ipd("maximum").is_null());
    let source = s.param_info(
        ANARI_RENDERER,
        "default",
        "shading",
        ANARI_STRING,
        "sourceExtension",
        ANARI_STRING,
    );
    assert_eq!(
        unsafe { CStr::from_ptr(source.cast()) }.to_str().unwrap(),
        "ANARI_CAVERAY_RENDERER_SHADING"
    );
    // No answer where there is none: a parameter without a range.
    assert!(s
        .param_info(
            ANARI_CAMERA,
            "perspective",
            "up",
            ANARI_FLOAT32_VEC3,
            "minimum",
            ANARI_FLOAT32
        )
        .is_null());
}

#[test]
fn device_and_world_properties() {
    let s = Session::new();
    let dev: ANARIObject = s.dev.cast();
    let renderers: usize = s
        .property(dev, "subtypes.renderer", ANARI_STRING_LIST)
        .unwrap();
    assert_eq!(
        unsafe { strings(renderers as *const *const c_char) },
        ["default", "directLight"]
    );
    let cameras: usize = s
        .property(dev, "subtypes.camera", ANARI_STRING_LIST)
        .unwrap();
    assert_eq!(
        unsafe { strings(cameras as *const *const c_char) },
        [
            "perspective",
            "orthographic",
            "matrix",
            "offAxis",
            "multiView"
        ]
    );
    let geometries: usize = s
        .property(dev, "subtypes.geometry", ANARI_STRING_LIST)
        .unwrap();
    assert_eq!(
        unsafe { strings(geometries as *const *const c_char) },
        [
            "isosurface",
            "triangle",
            "quad",
            "sphere",
            "cylinder",
            "cone",
            "curve"
        ]
    );
    let minor: i32 = s.property(dev, "version.minor", ANARI_INT32).unwrap();
    assert_eq!(
        minor,
        env!("CARGO_PKG_VERSION_MINOR").parse::<i32>().unwrap()
    );
    let name: usize = s.property(dev, "version.name", ANARI_STRING).unwrap();
    let name = unsafe { CStr::from_ptr(name as *const c_char) }
        .to_str()
        .unwrap();
    assert!(name.starts_with("caveray "), "{name}");

    // A world's bounds: its volumes' boxes.
    unsafe {
        let d = s.dev;
        let grid = api::anariNewArray3D(
            d,
            std::ptr::null(),
            None,
            std::ptr::null(),
            ANARI_FLOAT32,
            3,
            2,
            5,
        );
        let field = api::anariNewSpatialField(d, c("structuredRegular").as_ptr());
        api::anariSetParameter(
            d,
            field.cast(),
            c("data").as_ptr(),
            ANARI_ARRAY3D,
            (&grid as *const ANARIArray3D).cast(),
        );
        let origin = [1.0f32, -2.0, 0.5];
        let spacing = [0.5f32, 1.0, 0.25];
        api::anariSetParameter(
            d,
            field.cast(),
            c("origin").as_ptr(),
            ANARI_FLOAT32_VEC3,
            origin.as_ptr().cast(),
        );
        api::anariSetParameter(
            d,
            field.cast(),
            c("spacing").as_ptr(),
            ANARI_FLOAT32_VEC3,
            spacing.as_ptr().cast(),
        );
        api::anariCommitParameters(d, field.cast());
        let volume = api::anariNewVolume(d, c("transferFunction1D").as_ptr());
        api::anariSetParameter(
            d,
            volume.cast(),
            c("value").as_ptr(),
            ANARI_SPATIAL_FIELD,
            (&field as *const ANARISpatialField).cast(),
        );
        api::anariCommitParameters(d, volume.cast());
        let volumes = api::anariNewArray1D(
            d,
            (&volume as *const ANARIVolume).cast(),
            None,
            std::ptr::null(),
            ANARI_VOLUME,
            1,
        );
        let world = api::anariNewWorld(d);
        api::anariSetParameter(
            d,
            world.cast(),
            c("volume").as_ptr(),
            ANARI_ARRAY1D,
            (&volumes as *const ANARIArray1D).cast(),
        );
        api::anariCommitParameters(d, world.cast());
        let bounds: [f32; 6] = s
            .property(world.cast(), "bounds", ANARI_FLOAT32_BOX3)
            .unwrap();
        assert_eq!(bounds, [1.0, -2.0, 0.5, 2.0, -1.0, 1.5]);
        for o in [
            world.cast(),
            volumes.cast(),
            volume.cast(),
            field.cast(),
            grid.cast(),
        ] {
            api::anariRelease(d, o);
        }
    }
}
