//! Every C entry point, declared once: its C name, its implementation,
//! its signature and where the ANARI SDK loader finds it. From this table
//! the macro below generates
//! - the `#[no_mangle]` exports for hosts that link caveray directly,
//! - a compile-time check that each export has bindgen's signature of the
//!   headers (`sys.rs`),
//! - the typed `#[repr(C)]` virtual tables the SDK loader calls through,
//!   with each field's offset checked against its slot number.
//!
//! libanari treats our library and device handles as C++ objects of its
//! `LibraryImpl` / `DeviceImpl` classes: on Linux x86-64 (Itanium C++ ABI)
//! the object starts with a pointer to the class's virtual table, and a
//! virtual call passes the object as the first argument, like a C
//! function. Slot order is that of SDK 0.14 and later (docs/anari_loader.md).
//!
//! Table slots point at the implementations in `ops`, never at the
//! exports: inside the library an exported name could bind to libanari's
//! function of the same name.
#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use std::ffi::{c_char, c_int, c_void};

use super::sys::*;
use super::{helpers, ops, sys};

/// Emits the export for a row with a C name and checks it against bindgen;
/// `_` rows are loader-only; `unchecked` exports have no header
/// declaration (the loader's entry point).
macro_rules! export {
    (_, $imp:path, ($($arg:ident: $ty:ty),*) -> $ret:ty) => {};
    ($name:ident, $imp:path, ($($arg:ident: $ty:ty),*) -> $ret:ty) => {
        #[no_mangle]
        pub unsafe extern "C" fn $name($($arg: $ty),*) -> $ret {
            $imp($($arg),*)
        }
        const _: unsafe extern "C" fn($($ty),*) -> $ret = sys::$name;
    };
    (unchecked $name:ident, $imp:path, ($($arg:ident: $ty:ty),*) -> $ret:ty) => {
        #[no_mangle]
        pub unsafe extern "C" fn $name($($arg: $ty),*) -> $ret {
            $imp($($arg),*)
        }
    };
}

macro_rules! entry_points {
    (
        $(
            table $table:ident in $static:ident {
                $( [$slot:literal] $field:ident: $cname:tt = $m:ident::$f:ident
                   ($($arg:ident: $ty:ty),*) -> $ret:ty; )*
            }
        )*
        exports {
            $( $ename:ident = $em:ident::$ef:ident ($($earg:ident: $ety:ty),*) -> $eret:ty; )*
        }
        unchecked {
            $( $uname:ident = $um:ident::$uf:ident ($($uarg:ident: $uty:ty),*) -> $uret:ty; )*
        }
    ) => {
        $(
            /// A virtual table as the SDK loader reads it: one typed
            /// function pointer per slot, in slot order.
            #[repr(C)]
            pub struct $table {
                $( pub $field: unsafe extern "C" fn($($ty),*) -> $ret, )*
            }

            pub static $static: $table = $table { $( $field: $m::$f, )* };

            $(
                const _: () = assert!(
                    std::mem::offset_of!($table, $field)
                        == $slot * std::mem::size_of::<usize>()
                );
                export!($cname, $m::$f, ($($arg: $ty),*) -> $ret);
            )*
        )*
        $( export!($ename, $em::$ef, ($($earg: $ety),*) -> $eret); )*
        $( export!(unchecked $uname, $um::$uf, ($($uarg: $uty),*) -> $uret); )*
    };
}

entry_points! {
    table LibraryTable in LIBRARY_TABLE {
        [0] completeDestructor: _ = ops::library_complete_destructor(library: ANARILibrary) -> ();
        // anariUnloadLibrary calls the deleting destructor, then dlcloses.
        [1] deletingDestructor: anariUnloadLibrary = ops::unload_library(library: ANARILibrary) -> ();
        [2] newDevice: anariNewDevice = made::new_device(
            library: ANARILibrary, deviceSubtype: *const c_char) -> ANARIDevice;
        [3] newInitializedDevice: anariNewInitializedDevice = made::new_initialized_device(
            library: ANARILibrary, deviceSubtype: *const c_char,
            parameters: *const ANARIParameterValue) -> ANARIDevice;
        [4] getDeviceExtensions: anariGetDeviceExtensions = ops::get_device_extensions(
            library: ANARILibrary, deviceSubtype: *const c_char) -> *mut *const c_char;
        [5] getDeviceSubtypes: anariGetDeviceSubtypes = ops::get_device_subtypes(
            library: ANARILibrary) -> *mut *const c_char;
        [6] loadModule: anariLoadModule = ops::load_module(
            library: ANARILibrary, name: *const c_char) -> ();
        [7] unloadModule: anariUnloadModule = ops::unload_module(
            library: ANARILibrary, name: *const c_char) -> ();
    }

    table DeviceTable in DEVICE_TABLE {
        [0] newArray1D: anariNewArray1D = ops::new_array_1d(
            device: ANARIDevice, appMemory: *const c_void, deleter: ANARIMemoryDeleter,
            userData: *const c_void, dataType: ANARIDataType, numItems1: u64) -> ANARIArray1D;
        [1] newArray2D: anariNewArray2D = ops::new_array_2d(
            device: ANARIDevice, appMemory: *const c_void, deleter: ANARIMemoryDeleter,
            userData: *const c_void, dataType: ANARIDataType, numItems1: u64,
            numItems2: u64) -> ANARIArray2D;
        [2] newArray3D: anariNewArray3D = ops::new_array_3d(
            device: ANARIDevice, appMemory: *const c_void, deleter: ANARIMemoryDeleter,
            userData: *const c_void, dataType: ANARIDataType, numItems1: u64,
            numItems2: u64, numItems3: u64) -> ANARIArray3D;
        [3] newGeometry: anariNewGeometry = ops::new_geometry(
            device: ANARIDevice, type_: *const c_char) -> ANARIGeometry;
        [4] newMaterial: anariNewMaterial = ops::new_material(
            device: ANARIDevice, type_: *const c_char) -> ANARIMaterial;
        [5] newSampler: anariNewSampler = ops::new_sampler(
            device: ANARIDevice, type_: *const c_char) -> ANARISampler;
        [6] newSurface: anariNewSurface = ops::new_surface(device: ANARIDevice) -> ANARISurface;
        [7] newSpatialField: anariNewSpatialField = ops::new_spatial_field(
            device: ANARIDevice, type_: *const c_char) -> ANARISpatialField;
        [8] newVolume: anariNewVolume = ops::new_volume(
            device: ANARIDevice, type_: *const c_char) -> ANARIVolume;
        [9] newLight: anariNewLight = ops::new_light(
            device: ANARIDevice, type_: *const c_char) -> ANARILight;
        [10] newGroup: anariNewGroup = ops::new_group(device: ANARIDevice) -> ANARIGroup;
        [11] newInstance: anariNewInstance = ops::new_instance(
            device: ANARIDevice, type_: *const c_char) -> ANARIInstance;
        [12] newWorld: anariNewWorld = ops::new_world(device: ANARIDevice) -> ANARIWorld;
        [13] newCamera: anariNewCamera = ops::new_camera(
            device: ANARIDevice, type_: *const c_char) -> ANARICamera;
        [14] newRenderer: anariNewRenderer = ops::new_renderer(
            device: ANARIDevice, type_: *const c_char) -> ANARIRenderer;
        [15] newFrame: anariNewFrame = ops::new_frame(device: ANARIDevice) -> ANARIFrame;
        [16] setParameter: anariSetParameter = ops::set_parameter(
            device: ANARIDevice, object: ANARIObject, name: *const c_char,
            dataType: ANARIDataType, mem: *const c_void) -> ();
        [17] unsetParameter: anariUnsetParameter = ops::unset_parameter(
            device: ANARIDevice, object: ANARIObject, name: *const c_char) -> ();
        [18] unsetAllParameters: anariUnsetAllParameters = ops::unset_all_parameters(
            device: ANARIDevice, object: ANARIObject) -> ();
        [19] mapParameterArray1D: anariMapParameterArray1D = ops::map_parameter_array_1d(
            device: ANARIDevice, object: ANARIObject, name: *const c_char,
            dataType: ANARIDataType, numElements1: u64, elementStride: *mut u64) -> *mut c_void;
        [20] mapParameterArray2D: anariMapParameterArray2D = ops::map_parameter_array_2d(
            device: ANARIDevice, object: ANARIObject, name: *const c_char,
            dataType: ANARIDataType, numElements1: u64, numElements2: u64,
            elementStride: *mut u64) -> *mut c_void;
        [21] mapParameterArray3D: anariMapParameterArray3D = ops::map_parameter_array_3d(
            device: ANARIDevice, object: ANARIObject, name: *const c_char,
            dataType: ANARIDataType, numElements1: u64, numElements2: u64, numElements3: u64,
            elementStride: *mut u64) -> *mut c_void;
        [22] unmapParameterArray: anariUnmapParameterArray = ops::unmap_parameter_array(
            device: ANARIDevice, object: ANARIObject, name: *const c_char) -> ();
        [23] commitParameters: anariCommitParameters = ops::commit_parameters(
            device: ANARIDevice, object: ANARIObject) -> ();
        // Releasing the device itself comes here too, with object == device.
        [24] release: anariRelease = ops::release(device: ANARIDevice, object: ANARIObject) -> ();
        [25] retain: anariRetain = ops::retain(device: ANARIDevice, object: ANARIObject) -> ();
        [26] mapArray: anariMapArray = ops::map_array(
            device: ANARIDevice, array: ANARIArray) -> *mut c_void;
        [27] unmapArray: anariUnmapArray = ops::unmap_array(
            device: ANARIDevice, array: ANARIArray) -> ();
        [28] getProperty: anariGetProperty = ops::get_property(
            device: ANARIDevice, object: ANARIObject, name: *const c_char,
            dataType: ANARIDataType, mem: *mut c_void, size: u64,
            mask: ANARIWaitMask) -> c_int;
        [29] getObjectSubtypes: anariGetObjectSubtypes = ops::get_object_subtypes(
            device: ANARIDevice, objectType: ANARIDataType) -> *mut *const c_char;
        [30] getObjectInfo: anariGetObjectInfo = ops::get_object_info(
            device: ANARIDevice, objectType: ANARIDataType, objectSubtype: *const c_char,
            infoName: *const c_char, infoType: ANARIDataType) -> *const c_void;
        [31] getParameterInfo: anariGetParameterInfo = ops::get_parameter_info(
            device: ANARIDevice, objectType: ANARIDataType, objectSubtype: *const c_char,
            parameterName: *const c_char, parameterType: ANARIDataType,
            infoName: *const c_char, infoType: ANARIDataType) -> *const c_void;
        [32] frameBufferMap: anariMapFrame = ops::map_frame(
            device: ANARIDevice, frame: ANARIFrame, channel: *const c_char, width: *mut u32,
            height: *mut u32, pixelType: *mut ANARIDataType) -> *const c_void;
        [33] frameBufferUnmap: anariUnmapFrame = ops::unmap_frame(
            device: ANARIDevice, frame: ANARIFrame, channel: *const c_char) -> ();
        [34] renderFrame: anariRenderFrame = ops::render_frame(
            device: ANARIDevice, frame: ANARIFrame) -> ();
        [35] frameReady: anariFrameReady = ops::frame_ready(
            device: ANARIDevice, frame: ANARIFrame, mask: ANARIWaitMask) -> c_int;
        [36] discardFrame: anariDiscardFrame = ops::discard_frame(
            device: ANARIDevice, frame: ANARIFrame) -> ();
        [37] newObject: anariNewObject = ops::new_object(
            device: ANARIDevice, objectType: *const c_char, type_: *const c_char) -> ANARIObject;
        [38] getProcAddress: _ = ops::get_proc_address(
            device: ANARIDevice, name: *const c_char) -> *mut c_void;
        // The loader never calls the destructors; both drop the host's
        // reference, as anariRelease(device, device) does.
        [39] completeDestructor: _ = ops::device_destructor(device: ANARIDevice) -> ();
        [40] deletingDestructor: _ = ops::device_destructor(device: ANARIDevice) -> ();
    }

    exports {
        anariLoadLibrary = made::load_library(
            name: *const c_char, statusCallback: ANARIStatusCallback,
            statusCallbackUserData: *const c_void) -> ANARILibrary;
        caverayPinholeFromScreen = helpers::pinhole_from_screen(
            lowerLeft: *const f32, lowerRight: *const f32, upperRight: *const f32,
            eye: *const f32, out: *mut CaverayPinhole) -> ANARIStatusCode;
        caverayPinholeFromMatrices = helpers::pinhole_from_matrices(
            view: *const f32, proj: *const f32, out: *mut CaverayPinhole) -> ANARIStatusCode;
        caverayMatricesFromScreen = helpers::matrices_from_screen(
            lowerLeft: *const f32, lowerRight: *const f32, upperRight: *const f32,
            eye: *const f32, nearClip: f32, farClip: f32, view: *mut f32,
            proj: *mut f32) -> ANARIStatusCode;
        caverayLastError = helpers::last_error() -> *const c_char;
    }

    // What libanari's anariLoadLibrary looks up after dlopen; no header
    // declares it.
    unchecked {
        anari_library_caveray_new_library = made::new_library(
            dl_handle: *mut c_void, status_callback: ANARIStatusCallback,
            status_user: *const c_void) -> *mut c_void;
    }
}

/// The entry points that make handles. A handle points at its loader
/// table, so these sit beside the tables and hand them to `ops`.
mod made {
    use std::ffi::{c_char, c_void};

    use super::super::handles::Tables;
    use super::super::ops;
    use super::super::sys::*;
    use super::{DEVICE_TABLE, LIBRARY_TABLE};

    fn tables() -> Tables {
        Tables {
            library: std::ptr::from_ref(&LIBRARY_TABLE).cast(),
            device: std::ptr::from_ref(&DEVICE_TABLE).cast(),
        }
    }

    pub unsafe extern "C" fn load_library(
        name: *const c_char,
        status_callback: ANARIStatusCallback,
        user: *const c_void,
    ) -> ANARILibrary {
        ops::load_library(name, status_callback, user, tables())
    }

    pub unsafe extern "C" fn new_library(
        dl_handle: *mut c_void,
        status_callback: ANARIStatusCallback,
        user: *const c_void,
    ) -> *mut c_void {
        ops::new_library(dl_handle, status_callback, user, tables())
    }

    pub unsafe extern "C" fn new_device(lib: ANARILibrary, subtype: *const c_char) -> ANARIDevice {
        ops::new_device(lib, subtype, tables())
    }

    pub unsafe extern "C" fn new_initialized_device(
        lib: ANARILibrary,
        subtype: *const c_char,
        params: *const ANARIParameterValue,
    ) -> ANARIDevice {
        ops::new_initialized_device(lib, subtype, params, tables())
    }
}
