//! The implementation of every ANARI entry point. `entry_points.rs`
//! declares each once; its exports and the loader's virtual tables both
//! point here, so direct linkage and the SDK loader share one code path.
//! These are `extern "C"` but not exported: calling an exported symbol from
//! inside the library could bind to the SDK's libanari of the same name.
#![allow(clippy::missing_safety_doc)]

use std::ffi::{c_char, c_int, c_void};

use super::convert::{input, string};
use super::gate::finish_teardowns;
use super::handles::{DeviceHandle, DeviceRef, LibraryHandle, Tables};
use super::info;
use super::status::{call_error, emit, guard, set_library_callback, Callback};
use super::sys::*;
use crate::device::{
    object_kind, DataType, Device, FrameSlot, HostMemory, OnDone, Property, Severity, Status,
    StatusCode, Subject,
};

/// Runs `f` on the live device behind `dev`, then delivers the messages the
/// call produced, after the device is unlocked (a callback may call us).
fn with_device<R: Clone>(
    dev: ANARIDevice,
    call: &str,
    neutral: R,
    f: impl FnOnce(&DeviceRef, &mut Device) -> R,
) -> R {
    guard(call, neutral.clone(), || {
        let Some(d) = DeviceHandle::get(dev) else {
            let why = if dev.is_null() {
                "the device handle is NULL".to_owned()
            } else {
                format!("{dev:p} is not a live caveray device (released, or not a device)")
            };
            call_error(StatusCode::InvalidArgument, format!("{call}: {why}"));
            return neutral;
        };
        let (r, statuses, due) = {
            let mut device = d.lock();
            let r = f(&d, &mut device);
            (r, device.take_statuses(), device.take_due())
        };
        let cb = d.callback();
        for s in &statuses {
            d.gate.call(|| emit(cb, d.ptr(), s));
        }
        // Each passes the gate itself (`completion`).
        for done in due {
            done();
        }
        r
    })
}

/// `with_device` for calls with one string argument, which is checked
/// first and reported if it is NULL or not UTF-8.
fn with_named<R: Clone>(
    dev: ANARIDevice,
    call: &str,
    name: *const c_char,
    what: &str,
    neutral: R,
    f: impl FnOnce(&DeviceRef, &mut Device, String) -> R,
) -> R {
    with_device(dev, call, neutral.clone(), |d, device| {
        // SAFETY: the host passes a C string or NULL.
        match unsafe { string(name, what) } {
            Ok(n) => f(d, device, n),
            Err(e) => {
                device_error(device, StatusCode::InvalidArgument, format!("{call}: {e}"));
                neutral
            }
        }
    })
}

fn target(d: &DeviceRef, obj: ANARIObject) -> Subject {
    if obj == d.ptr() {
        Subject::Device
    } else {
        Subject::Object(obj as usize as u64)
    }
}

fn handle<T>(h: u64) -> *mut T {
    h as usize as *mut T
}

fn device_error(device: &mut Device, code: StatusCode, message: String) {
    device.report_error(code, message);
}

// ---- library ----

pub unsafe fn load_library(
    name: *const c_char,
    status_callback: ANARIStatusCallback,
    user: *const c_void,
    tables: Tables,
) -> ANARILibrary {
    guard("anariLoadLibrary", std::ptr::null_mut(), || {
        let cb = Callback {
            function: status_callback,
            user: user as usize,
        };
        set_library_callback(cb);
        let name = match string(name, "the library name") {
            Ok(n) => n,
            Err(e) => {
                call_error(
                    StatusCode::InvalidArgument,
                    format!("anariLoadLibrary: {e}"),
                );
                return std::ptr::null_mut();
            }
        };
        let wanted = if name == "environment" {
            std::env::var("ANARI_LIBRARY").unwrap_or_else(|_| "caveray".into())
        } else {
            name.clone()
        };
        if !matches!(wanted.as_str(), "caveray" | "default") {
            call_error(
                StatusCode::UnsupportedDevice,
                format!(
                    "anariLoadLibrary: this is caveray linked directly, so it loads only 'caveray', \
                     not '{wanted}'; use the ANARI SDK's libanari to load other libraries"
                ),
            );
            return std::ptr::null_mut();
        }
        LibraryHandle::create(tables, std::ptr::null_mut(), cb).cast()
    })
}

pub unsafe fn new_library(
    dl_handle: *mut c_void,
    status_callback: ANARIStatusCallback,
    user: *const c_void,
    tables: Tables,
) -> *mut c_void {
    guard(
        "anari_library_caveray_new_library",
        std::ptr::null_mut(),
        || {
            let cb = Callback {
                function: status_callback,
                user: user as usize,
            };
            set_library_callback(cb);
            LibraryHandle::create(tables, dl_handle, cb).cast()
        },
    )
}

pub unsafe extern "C" fn unload_library(lib: ANARILibrary) {
    guard("anariUnloadLibrary", (), || {
        // The loader unloads the code next: released devices' teardowns
        // must be done first.
        finish_teardowns();
        if !LibraryHandle::destroy(lib) {
            call_error(
                StatusCode::InvalidArgument,
                format!("anariUnloadLibrary: {lib:p} is not a loaded caveray library"),
            );
        }
    })
}

/// The loader's complete destructor: the library owns nothing but its own
/// memory, which only the deleting destructor frees.
pub unsafe extern "C" fn library_complete_destructor(_lib: ANARILibrary) {}

fn library(lib: ANARILibrary, call: &str) -> Option<&'static LibraryHandle> {
    let l = LibraryHandle::get(lib);
    if l.is_none() {
        let why = if lib.is_null() {
            "the library handle is NULL".to_owned()
        } else {
            format!("{lib:p} is not a loaded caveray library")
        };
        call_error(StatusCode::InvalidArgument, format!("{call}: {why}"));
    }
    l
}

/// caveray is one library with no loadable modules.
unsafe fn no_modules(lib: ANARILibrary, call: &str, name: *const c_char, what: &str) {
    guard(call, (), || {
        if let Some(l) = library(lib, call) {
            // SAFETY: the host passes a C string or NULL.
            let name = unsafe { string(name, "the module name") }.unwrap_or_default();
            emit(
                l.callback(),
                std::ptr::null_mut(),
                &Status {
                    severity: Severity::Warning,
                    code: StatusCode::InvalidArgument,
                    source: 0,
                    source_kind: DataType::LIBRARY,
                    message: format!("{call}: caveray has no modules; '{name}' {what}"),
                },
            );
        }
    })
}

pub unsafe extern "C" fn load_module(lib: ANARILibrary, name: *const c_char) {
    no_modules(lib, "anariLoadModule", name, "was not loaded")
}

pub unsafe extern "C" fn unload_module(lib: ANARILibrary, name: *const c_char) {
    no_modules(lib, "anariUnloadModule", name, "is not loaded")
}

fn check_device_subtype(l: &LibraryHandle, call: &str, subtype: *const c_char) -> bool {
    // SAFETY: the host passes a C string or NULL.
    let sub = unsafe { string(subtype, "the device subtype") };
    match sub.as_deref() {
        Ok("default") | Ok("caveray") => true,
        other => {
            let what = match other {
                Ok(s) => format!("device subtype '{s}' does not exist; caveray has 'default'"),
                Err(e) => e.clone(),
            };
            emit(
                l.callback(),
                std::ptr::null_mut(),
                &Status {
                    severity: Severity::Error,
                    code: StatusCode::UnsupportedDevice,
                    source: 0,
                    source_kind: DataType::LIBRARY,
                    message: format!("{call}: {what}"),
                },
            );
            false
        }
    }
}

pub unsafe fn new_device(lib: ANARILibrary, subtype: *const c_char, tables: Tables) -> ANARIDevice {
    guard("anariNewDevice", std::ptr::null_mut(), || {
        match library(lib, "anariNewDevice") {
            Some(l) if check_device_subtype(l, "anariNewDevice", subtype) => {
                DeviceHandle::create(tables, l.callback()).cast()
            }
            _ => std::ptr::null_mut(),
        }
    })
}

pub unsafe fn new_initialized_device(
    lib: ANARILibrary,
    subtype: *const c_char,
    params: *const ANARIParameterValue,
    tables: Tables,
) -> ANARIDevice {
    let dev = new_device(lib, subtype, tables);
    if dev.is_null() || params.is_null() {
        return dev;
    }
    let mut p = params;
    while !(*p).name.is_null() {
        set_parameter(dev, dev, (*p).name, (*p).type_, (*p).value);
        p = p.add(1);
    }
    commit_parameters(dev, dev);
    dev
}

pub unsafe extern "C" fn get_device_subtypes(lib: ANARILibrary) -> *mut *const c_char {
    guard(
        "anariGetDeviceSubtypes",
        std::ptr::null_mut(),
        || match library(lib, "anariGetDeviceSubtypes") {
            Some(_) => info::device_subtypes().cast_mut(),
            None => std::ptr::null_mut(),
        },
    )
}

pub unsafe extern "C" fn get_device_extensions(
    lib: ANARILibrary,
    subtype: *const c_char,
) -> *mut *const c_char {
    guard(
        "anariGetDeviceExtensions",
        std::ptr::null_mut(),
        || match library(lib, "anariGetDeviceExtensions") {
            Some(l) if check_device_subtype(l, "anariGetDeviceExtensions", subtype) => {
                info::extensions().cast_mut()
            }
            _ => std::ptr::null_mut(),
        },
    )
}

// ---- arrays ----

/// The host's memory behind a shared array; dropping it calls the
/// host's deleter, once.
struct AppMemory {
    ptr: *const c_void,
    deleter: ANARIMemoryDeleter,
    user: *const c_void,
}

// SAFETY: the pointers are the host's; ANARI lets the device release
// shared memory from whichever thread drops the array.
unsafe impl Send for AppMemory {}

impl HostMemory for AppMemory {
    fn ptr(&self) -> *const u8 {
        self.ptr.cast()
    }
    fn disown(&mut self) {
        self.deleter = None;
    }
    fn captured(&self) -> bool {
        self.deleter.is_some()
    }
}

impl Drop for AppMemory {
    fn drop(&mut self) {
        if let Some(d) = self.deleter.take() {
            // SAFETY: the host registered the deleter for this memory.
            unsafe { d(self.user, self.ptr) }
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn new_array(
    dev: ANARIDevice,
    call: &str,
    kind: DataType,
    app_memory: *const c_void,
    deleter: ANARIMemoryDeleter,
    user: *const c_void,
    element: ANARIDataType,
    dims: [u64; 3],
) -> *mut c_void {
    with_device(dev, call, std::ptr::null_mut(), |_, device| {
        let memory: Option<Box<dyn HostMemory>> = (!app_memory.is_null()).then(|| {
            Box::new(AppMemory {
                ptr: app_memory,
                deleter,
                user,
            }) as Box<dyn HostMemory>
        });
        match device.new_array(kind, element, dims, memory) {
            Ok(h) => handle(h),
            Err(memory) => {
                // No array exists, so the memory stays the host's.
                if let Some(mut m) = memory {
                    m.disown();
                }
                std::ptr::null_mut()
            }
        }
    })
}

pub unsafe extern "C" fn new_array_1d(
    dev: ANARIDevice,
    app_memory: *const c_void,
    deleter: ANARIMemoryDeleter,
    user: *const c_void,
    element: ANARIDataType,
    n1: u64,
) -> ANARIArray1D {
    new_array(
        dev,
        "anariNewArray1D",
        DataType::ARRAY1D,
        app_memory,
        deleter,
        user,
        element,
        [n1, 1, 1],
    )
}

pub unsafe extern "C" fn new_array_2d(
    dev: ANARIDevice,
    app_memory: *const c_void,
    deleter: ANARIMemoryDeleter,
    user: *const c_void,
    element: ANARIDataType,
    n1: u64,
    n2: u64,
) -> ANARIArray2D {
    new_array(
        dev,
        "anariNewArray2D",
        DataType::ARRAY2D,
        app_memory,
        deleter,
        user,
        element,
        [n1, n2, 1],
    )
}

#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn new_array_3d(
    dev: ANARIDevice,
    app_memory: *const c_void,
    deleter: ANARIMemoryDeleter,
    user: *const c_void,
    element: ANARIDataType,
    n1: u64,
    n2: u64,
    n3: u64,
) -> ANARIArray3D {
    new_array(
        dev,
        "anariNewArray3D",
        DataType::ARRAY3D,
        app_memory,
        deleter,
        user,
        element,
        [n1, n2, n3],
    )
}

pub unsafe extern "C" fn map_array(dev: ANARIDevice, array: ANARIArray) -> *mut c_void {
    with_device(dev, "anariMapArray", std::ptr::null_mut(), |_, d| {
        d.map_array(array as usize as u64).cast()
    })
}

pub unsafe extern "C" fn unmap_array(dev: ANARIDevice, array: ANARIArray) {
    with_device(dev, "anariUnmapArray", (), |_, d| {
        d.unmap_array(array as usize as u64)
    })
}

// ---- objects ----

unsafe fn new_object_of(
    dev: ANARIDevice,
    call: &str,
    kind: DataType,
    subtype: *const c_char,
) -> *mut c_void {
    with_device(dev, call, std::ptr::null_mut(), |_, d| {
        let sub = if subtype.is_null()
            && matches!(
                kind,
                DataType::SURFACE | DataType::GROUP | DataType::WORLD | DataType::FRAME
            ) {
            Ok(String::new())
        } else {
            // SAFETY: the host passes a C string or NULL.
            unsafe { string(subtype, "the subtype") }
        };
        match sub {
            Ok(s) => handle(d.new_object(kind, &s)),
            Err(e) => {
                device_error(d, StatusCode::InvalidArgument, format!("{call}: {e}"));
                std::ptr::null_mut()
            }
        }
    })
}

macro_rules! new_with_subtype {
    ($($fn:ident, $call:literal, $kind:ident;)*) => {$(
        pub unsafe extern "C" fn $fn(dev: ANARIDevice, subtype: *const c_char) -> *mut c_void {
            new_object_of(dev, $call, DataType::$kind, subtype)
        }
    )*};
}

new_with_subtype! {
    new_light, "anariNewLight", LIGHT;
    new_camera, "anariNewCamera", CAMERA;
    new_geometry, "anariNewGeometry", GEOMETRY;
    new_spatial_field, "anariNewSpatialField", SPATIAL_FIELD;
    new_volume, "anariNewVolume", VOLUME;
    new_material, "anariNewMaterial", MATERIAL;
    new_sampler, "anariNewSampler", SAMPLER;
    new_instance, "anariNewInstance", INSTANCE;
    new_renderer, "anariNewRenderer", RENDERER;
}

pub unsafe extern "C" fn new_surface(dev: ANARIDevice) -> ANARISurface {
    new_object_of(dev, "anariNewSurface", DataType::SURFACE, std::ptr::null())
}
pub unsafe extern "C" fn new_group(dev: ANARIDevice) -> ANARIGroup {
    new_object_of(dev, "anariNewGroup", DataType::GROUP, std::ptr::null())
}
pub unsafe extern "C" fn new_world(dev: ANARIDevice) -> ANARIWorld {
    new_object_of(dev, "anariNewWorld", DataType::WORLD, std::ptr::null())
}
pub unsafe extern "C" fn new_frame(dev: ANARIDevice) -> ANARIFrame {
    new_object_of(dev, "anariNewFrame", DataType::FRAME, std::ptr::null())
}

pub unsafe extern "C" fn new_object(
    dev: ANARIDevice,
    object_type: *const c_char,
    subtype: *const c_char,
) -> ANARIObject {
    let kind = string(object_type, "the object type")
        .and_then(|t| object_kind(&t).ok_or_else(|| format!("'{t}' is not an ANARI object type")));
    match kind {
        Ok(kind) => new_object_of(dev, "anariNewObject", kind, subtype),
        Err(e) => with_device(dev, "anariNewObject", std::ptr::null_mut(), |_, d| {
            device_error(
                d,
                StatusCode::InvalidArgument,
                format!("anariNewObject: {e}"),
            );
            std::ptr::null_mut()
        }),
    }
}

// ---- parameters ----

pub unsafe extern "C" fn set_parameter(
    dev: ANARIDevice,
    obj: ANARIObject,
    name: *const c_char,
    ty: ANARIDataType,
    mem: *const c_void,
) {
    with_device(dev, "anariSetParameter", (), |d, device| {
        // SAFETY: the host passes a C string and a value of type `ty`.
        let parsed = unsafe { string(name, "the parameter name") }
            .and_then(|n| unsafe { input(ty, mem) }.map(|v| (n, v)));
        match parsed {
            Ok((n, v)) => device.set_param(target(d, obj), &n, v),
            Err(e) => device_error(
                device,
                StatusCode::InvalidArgument,
                format!("anariSetParameter: {e}"),
            ),
        }
    })
}

pub unsafe extern "C" fn unset_parameter(dev: ANARIDevice, obj: ANARIObject, name: *const c_char) {
    with_named(
        dev,
        "anariUnsetParameter",
        name,
        "the parameter name",
        (),
        |d, device, n| device.unset_param(target(d, obj), &n),
    )
}

pub unsafe extern "C" fn unset_all_parameters(dev: ANARIDevice, obj: ANARIObject) {
    with_device(dev, "anariUnsetAllParameters", (), |d, device| {
        device.unset_all_params(target(d, obj))
    })
}

unsafe fn map_parameter_array(
    dev: ANARIDevice,
    obj: ANARIObject,
    name: *const c_char,
    ty: ANARIDataType,
    kind: DataType,
    dims: [u64; 3],
    stride: *mut u64,
) -> *mut c_void {
    let (ptr, element) = with_named(
        dev,
        "anariMapParameterArray",
        name,
        "the parameter name",
        (std::ptr::null_mut(), 0),
        |_, device, n| device.map_param_array(obj as usize as u64, &n, kind, ty, dims),
    );
    if !stride.is_null() {
        // SAFETY: the host passes room for one uint64_t or NULL.
        stride.write(element);
    }
    ptr.cast()
}

pub unsafe extern "C" fn map_parameter_array_1d(
    dev: ANARIDevice,
    obj: ANARIObject,
    name: *const c_char,
    ty: ANARIDataType,
    n1: u64,
    stride: *mut u64,
) -> *mut c_void {
    map_parameter_array(dev, obj, name, ty, DataType::ARRAY1D, [n1, 1, 1], stride)
}

pub unsafe extern "C" fn map_parameter_array_2d(
    dev: ANARIDevice,
    obj: ANARIObject,
    name: *const c_char,
    ty: ANARIDataType,
    n1: u64,
    n2: u64,
    stride: *mut u64,
) -> *mut c_void {
    map_parameter_array(dev, obj, name, ty, DataType::ARRAY2D, [n1, n2, 1], stride)
}

#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn map_parameter_array_3d(
    dev: ANARIDevice,
    obj: ANARIObject,
    name: *const c_char,
    ty: ANARIDataType,
    n1: u64,
    n2: u64,
    n3: u64,
    stride: *mut u64,
) -> *mut c_void {
    map_parameter_array(dev, obj, name, ty, DataType::ARRAY3D, [n1, n2, n3], stride)
}

pub unsafe extern "C" fn unmap_parameter_array(
    dev: ANARIDevice,
    obj: ANARIObject,
    name: *const c_char,
) {
    with_named(
        dev,
        "anariUnmapParameterArray",
        name,
        "the parameter name",
        (),
        |_, device, n| device.unmap_param_array(obj as usize as u64, &n),
    )
}

pub unsafe extern "C" fn commit_parameters(dev: ANARIDevice, obj: ANARIObject) {
    with_device(dev, "anariCommitParameters", (), |d, device| {
        let t = target(d, obj);
        device.commit(t);
        if t == Subject::Device {
            let function = device
                .device_param("statusCallback")
                .and_then(|v| v.pointer())
                .filter(|&a| a != 0)
                // SAFETY: the host declared this value an ANARIStatusCallback.
                .map(|a| unsafe {
                    std::mem::transmute::<
                        usize,
                        unsafe extern "C" fn(
                            *const c_void,
                            ANARIDevice,
                            ANARIObject,
                            ANARIDataType,
                            ANARIStatusSeverity,
                            ANARIStatusCode,
                            *const c_char,
                        ),
                    >(a)
                });
            let user = device
                .device_param("statusCallbackUserData")
                .and_then(|v| v.pointer())
                .unwrap_or(0);
            d.set_callback(match function {
                Some(f) => Callback {
                    function: Some(f),
                    user,
                },
                None => d.default_callback(),
            });
        }
    })
}

pub unsafe extern "C" fn release(dev: ANARIDevice, obj: ANARIObject) {
    with_device(dev, "anariRelease", (), |d, device| match target(d, obj) {
        // The device goes when this call's own reference is dropped too.
        Subject::Device => DeviceHandle::release(d.ptr().cast()),
        Subject::Object(h) => device.release(h),
    })
}

pub unsafe extern "C" fn retain(dev: ANARIDevice, obj: ANARIObject) {
    with_device(dev, "anariRetain", (), |d, device| match target(d, obj) {
        Subject::Device => d.retain(),
        Subject::Object(h) => device.retain(h),
    })
}

// ---- introspection ----

pub unsafe extern "C" fn get_object_subtypes(
    dev: ANARIDevice,
    kind: ANARIDataType,
) -> *mut *const c_char {
    with_device(
        dev,
        "anariGetObjectSubtypes",
        std::ptr::null_mut(),
        |_, _| info::object_subtypes(kind).cast_mut(),
    )
}

pub unsafe extern "C" fn get_object_info(
    dev: ANARIDevice,
    kind: ANARIDataType,
    subtype: *const c_char,
    info_name: *const c_char,
    info_type: ANARIDataType,
) -> *const c_void {
    with_named(
        dev,
        "anariGetObjectInfo",
        info_name,
        "the info name",
        std::ptr::null(),
        |_, _, n| {
            // SAFETY: the host passes a C string or NULL (no subtype).
            let sub = unsafe { string(subtype, "the subtype") }.unwrap_or_default();
            info::object_info(kind, &sub, &n, info_type)
        },
    )
}

pub unsafe extern "C" fn get_parameter_info(
    dev: ANARIDevice,
    kind: ANARIDataType,
    subtype: *const c_char,
    param: *const c_char,
    param_type: ANARIDataType,
    info_name: *const c_char,
    info_type: ANARIDataType,
) -> *const c_void {
    with_device(
        dev,
        "anariGetParameterInfo",
        std::ptr::null(),
        |_, device| {
            // SAFETY: the host passes C strings.
            let sub = unsafe { string(subtype, "the subtype") }.unwrap_or_default();
            let names = unsafe { string(param, "the parameter name") }
                .and_then(|p| unsafe { string(info_name, "the info name") }.map(|i| (p, i)));
            match names {
                Ok((p, i)) => info::parameter_info(kind, &sub, &p, param_type, &i, info_type),
                Err(e) => {
                    device_error(
                        device,
                        StatusCode::InvalidArgument,
                        format!("anariGetParameterInfo: {e}"),
                    );
                    std::ptr::null()
                }
            }
        },
    )
}

pub unsafe extern "C" fn get_property(
    dev: ANARIDevice,
    obj: ANARIObject,
    name: *const c_char,
    ty: ANARIDataType,
    mem: *mut c_void,
    size: u64,
    mask: ANARIWaitMask,
) -> c_int {
    if mask & 1 != 0 && !obj.is_null() && obj != dev {
        // Only frames have properties that change while rendering.
        let is_frame = with_device(dev, "anariGetProperty", false, |_, device| {
            device.kind_of(obj as usize as u64) == Some(DataType::FRAME)
        });
        if is_frame && !wait_for(dev, "anariGetProperty", obj) {
            return 0;
        }
    }
    let wait = mask & 1 != 0;
    let value = when_idle("anariGetProperty", || {
        with_named(
            dev,
            "anariGetProperty",
            name,
            "the property name",
            Ok(None),
            |d, device, name| device.try_property(target(d, obj), &name, wait),
        )
    });
    let Some(value) = value else {
        return 0;
    };
    with_named(
        dev,
        "anariGetProperty",
        name,
        "the property name",
        0,
        |_, device, name| {
            let (expected, bytes): (DataType, Vec<u8>) = match value {
                Property::Int32(v) => (DataType::INT32, v.to_ne_bytes().to_vec()),
                Property::UInt64(v) => (DataType::UINT64, v.to_ne_bytes().to_vec()),
                Property::Float32(v) => (DataType::FLOAT32, v.to_ne_bytes().to_vec()),
                Property::Box3(b) => (
                    DataType::FLOAT32_BOX3,
                    b.iter().flat_map(|x| x.to_ne_bytes()).collect(),
                ),
                Property::Text(t) => (
                    DataType::STRING,
                    (t.as_ptr() as usize).to_ne_bytes().to_vec(),
                ),
                Property::Extensions => (
                    DataType::STRING_LIST,
                    (info::extensions() as usize).to_ne_bytes().to_vec(),
                ),
                Property::Subtypes(kind) => (
                    DataType::STRING_LIST,
                    (info::object_subtypes(kind as i32) as usize)
                        .to_ne_bytes()
                        .to_vec(),
                ),
            };
            if ty != expected as i32 {
                device_error(
                    device,
                    StatusCode::InvalidArgument,
                    format!(
                        "anariGetProperty: property '{name}' is {expected}, not {}",
                        DataType::from_code(ty)
                            .map_or_else(|| ty.to_string(), |t| t.name().to_owned())
                    ),
                );
                return 0;
            }
            if mem.is_null() || size < bytes.len() as u64 {
                device_error(
                device,
                StatusCode::InvalidArgument,
                format!("anariGetProperty: property '{name}' needs {} bytes at a non-NULL address, got {size}", bytes.len()),
            );
                return 0;
            }
            // SAFETY: the host gave `size` writable bytes at `mem`.
            unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), mem.cast(), bytes.len()) };
            1
        },
    )
}

// ---- frames ----

pub unsafe extern "C" fn map_frame(
    dev: ANARIDevice,
    frame: ANARIFrame,
    channel: *const c_char,
    width: *mut u32,
    height: *mut u32,
    pixel_type: *mut ANARIDataType,
) -> *const c_void {
    let write = |w: u32, h: u32, t: i32| {
        // SAFETY: each out-pointer is NULL or room for one value.
        unsafe {
            if !width.is_null() {
                width.write(w);
            }
            if !height.is_null() {
                height.write(h);
            }
            if !pixel_type.is_null() {
                pixel_type.write(t);
            }
        }
    };
    write(0, 0, DataType::UNKNOWN as i32);
    if !wait_for(dev, "anariMapFrame", frame) {
        return std::ptr::null();
    }
    when_idle("anariMapFrame", || {
        with_named(
            dev,
            "anariMapFrame",
            channel,
            "the channel name",
            Ok(std::ptr::null()),
            |_, device, channel| {
                Ok(
                    match device.try_map_frame(frame as usize as u64, &channel)? {
                        Some(m) => {
                            write(m.size.x, m.size.y, m.ty as i32);
                            m.ptr.cast()
                        }
                        None => std::ptr::null(),
                    },
                )
            },
        )
    })
}

pub unsafe extern "C" fn unmap_frame(dev: ANARIDevice, frame: ANARIFrame, channel: *const c_char) {
    with_named(
        dev,
        "anariUnmapFrame",
        channel,
        "the channel name",
        (),
        |_, device, c| device.unmap_frame(frame as usize as u64, &c),
    )
}

pub unsafe extern "C" fn render_frame(dev: ANARIDevice, frame: ANARIFrame) {
    let h = frame as usize as u64;
    let mut on_done = None;
    let mut read = false;
    when_idle("anariRenderFrame", || {
        with_device(dev, "anariRenderFrame", Ok(()), |d, device| {
            if !std::mem::replace(&mut read, true) {
                on_done = completion(d, device, h);
            }
            device.start_render(h, &mut on_done)
        })
    })
}

/// The frame's completion callback as the device calls it, if it has one.
fn completion(d: &DeviceRef, device: &mut Device, h: u64) -> Option<OnDone> {
    let callback = device
        .committed(h, "frameCompletionCallback")
        .and_then(|v| v.pointer())
        .filter(|&a| a != 0);
    let user = device
        .committed(h, "frameCompletionCallbackUserData")
        .and_then(|v| v.pointer())
        .unwrap_or(0);
    let device_ptr = d.ptr() as usize;
    let gate = std::sync::Arc::clone(&d.gate);
    callback.map(|f| {
        Box::new(move || {
            // SAFETY: the host declared this value an ANARIFrameCompletionCallback.
            let f: unsafe extern "C" fn(*const c_void, ANARIDevice, ANARIFrame) =
                unsafe { std::mem::transmute(f) };
            gate.call(|| unsafe {
                f(
                    user as *const c_void,
                    device_ptr as ANARIDevice,
                    h as usize as ANARIFrame,
                )
            })
        }) as OnDone
    })
}

/// Calls `f` until it stops answering that a frame is rendering, waiting
/// for that render between calls without holding the device, so that
/// callbacks on the render thread may call into the device meanwhile.
fn when_idle<R>(call: &str, mut f: impl FnMut() -> Result<R, std::sync::Arc<FrameSlot>>) -> R {
    loop {
        match f() {
            Ok(r) => return r,
            Err(slot) => guard(call, (), || drop(slot.wait())),
        }
    }
}

/// Waits for a frame without holding the device, so that callbacks on the
/// render thread may call into the device meanwhile.
fn wait_for(dev: ANARIDevice, call: &str, frame: ANARIFrame) -> bool {
    let slot = with_device(dev, call, None, |_, device| {
        device.frame_slot(frame as usize as u64, call)
    });
    match slot {
        Some(s) => {
            guard(call, (), || drop(s.wait()));
            true
        }
        None => false,
    }
}

pub unsafe extern "C" fn frame_ready(
    dev: ANARIDevice,
    frame: ANARIFrame,
    mask: ANARIWaitMask,
) -> c_int {
    if mask & 1 != 0 {
        return c_int::from(wait_for(dev, "anariFrameReady", frame));
    }
    with_device(dev, "anariFrameReady", 0, |_, device| {
        c_int::from(device.frame_ready(frame as usize as u64))
    })
}

pub unsafe extern "C" fn discard_frame(dev: ANARIDevice, frame: ANARIFrame) {
    with_device(dev, "anariDiscardFrame", (), |_, device| {
        device.discard_frame(frame as usize as u64)
    })
}

/// The loader's `getProcAddress`: caveray has no extra entry points there.
pub unsafe extern "C" fn get_proc_address(_dev: ANARIDevice, _name: *const c_char) -> *mut c_void {
    std::ptr::null_mut()
}

/// Slots 39/40 of the device table (the loader never calls them): drop the
/// host's reference, as `anariRelease(device, device)` does.
pub unsafe extern "C" fn device_destructor(dev: ANARIDevice) {
    release(dev, dev)
}
