//! The exported C symbols: `include/anari/anari.h`'s entry points, the SDK
//! loader's entry point and `include/anari/caveray.h`'s helpers. Each only
//! forwards; `exports_match_the_headers` below makes the build fail if a
//! signature differs from bindgen's declaration of the headers.
#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use std::ffi::{c_char, c_int, c_void};

use super::sys::*;
use super::{helpers, ops};

#[no_mangle]
pub unsafe extern "C" fn anariLoadLibrary(
    name: *const c_char,
    statusCallback: ANARIStatusCallback,
    statusCallbackUserData: *const c_void,
) -> ANARILibrary {
    ops::load_library(name, statusCallback, statusCallbackUserData)
}

#[no_mangle]
pub unsafe extern "C" fn anariUnloadLibrary(library: ANARILibrary) {
    ops::unload_library(library)
}

#[no_mangle]
pub unsafe extern "C" fn anariLoadModule(library: ANARILibrary, name: *const c_char) {
    ops::load_module(library, name)
}

#[no_mangle]
pub unsafe extern "C" fn anariUnloadModule(library: ANARILibrary, name: *const c_char) {
    ops::unload_module(library, name)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewDevice(
    library: ANARILibrary,
    deviceSubtype: *const c_char,
) -> ANARIDevice {
    ops::new_device(library, deviceSubtype)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewInitializedDevice(
    library: ANARILibrary,
    deviceSubtype: *const c_char,
    parameters: *const ANARIParameterValue,
) -> ANARIDevice {
    ops::new_initialized_device(library, deviceSubtype, parameters)
}

#[no_mangle]
pub unsafe extern "C" fn anariGetDeviceSubtypes(library: ANARILibrary) -> *mut *const c_char {
    ops::get_device_subtypes(library)
}

#[no_mangle]
pub unsafe extern "C" fn anariGetDeviceExtensions(
    library: ANARILibrary,
    deviceSubtype: *const c_char,
) -> *mut *const c_char {
    ops::get_device_extensions(library, deviceSubtype)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewArray1D(
    device: ANARIDevice,
    appMemory: *const c_void,
    deleter: ANARIMemoryDeleter,
    userData: *const c_void,
    dataType: ANARIDataType,
    numItems1: u64,
) -> ANARIArray1D {
    ops::new_array_1d(device, appMemory, deleter, userData, dataType, numItems1)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewArray2D(
    device: ANARIDevice,
    appMemory: *const c_void,
    deleter: ANARIMemoryDeleter,
    userData: *const c_void,
    dataType: ANARIDataType,
    numItems1: u64,
    numItems2: u64,
) -> ANARIArray2D {
    ops::new_array_2d(
        device, appMemory, deleter, userData, dataType, numItems1, numItems2,
    )
}

#[no_mangle]
pub unsafe extern "C" fn anariNewArray3D(
    device: ANARIDevice,
    appMemory: *const c_void,
    deleter: ANARIMemoryDeleter,
    userData: *const c_void,
    dataType: ANARIDataType,
    numItems1: u64,
    numItems2: u64,
    numItems3: u64,
) -> ANARIArray3D {
    ops::new_array_3d(
        device, appMemory, deleter, userData, dataType, numItems1, numItems2, numItems3,
    )
}

#[no_mangle]
pub unsafe extern "C" fn anariMapArray(device: ANARIDevice, array: ANARIArray) -> *mut c_void {
    ops::map_array(device, array)
}

#[no_mangle]
pub unsafe extern "C" fn anariUnmapArray(device: ANARIDevice, array: ANARIArray) {
    ops::unmap_array(device, array)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewLight(device: ANARIDevice, type_: *const c_char) -> ANARILight {
    ops::new_light(device, type_)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewCamera(device: ANARIDevice, type_: *const c_char) -> ANARICamera {
    ops::new_camera(device, type_)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewGeometry(
    device: ANARIDevice,
    type_: *const c_char,
) -> ANARIGeometry {
    ops::new_geometry(device, type_)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewSpatialField(
    device: ANARIDevice,
    type_: *const c_char,
) -> ANARISpatialField {
    ops::new_spatial_field(device, type_)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewVolume(device: ANARIDevice, type_: *const c_char) -> ANARIVolume {
    ops::new_volume(device, type_)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewMaterial(
    device: ANARIDevice,
    type_: *const c_char,
) -> ANARIMaterial {
    ops::new_material(device, type_)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewSampler(
    device: ANARIDevice,
    type_: *const c_char,
) -> ANARISampler {
    ops::new_sampler(device, type_)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewInstance(
    device: ANARIDevice,
    type_: *const c_char,
) -> ANARIInstance {
    ops::new_instance(device, type_)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewRenderer(
    device: ANARIDevice,
    type_: *const c_char,
) -> ANARIRenderer {
    ops::new_renderer(device, type_)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewSurface(device: ANARIDevice) -> ANARISurface {
    ops::new_surface(device)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewGroup(device: ANARIDevice) -> ANARIGroup {
    ops::new_group(device)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewWorld(device: ANARIDevice) -> ANARIWorld {
    ops::new_world(device)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewFrame(device: ANARIDevice) -> ANARIFrame {
    ops::new_frame(device)
}

#[no_mangle]
pub unsafe extern "C" fn anariNewObject(
    device: ANARIDevice,
    objectType: *const c_char,
    type_: *const c_char,
) -> ANARIObject {
    ops::new_object(device, objectType, type_)
}

#[no_mangle]
pub unsafe extern "C" fn anariRelease(device: ANARIDevice, object: ANARIObject) {
    ops::release(device, object)
}

#[no_mangle]
pub unsafe extern "C" fn anariRetain(device: ANARIDevice, object: ANARIObject) {
    ops::retain(device, object)
}

#[no_mangle]
pub unsafe extern "C" fn anariSetParameter(
    device: ANARIDevice,
    object: ANARIObject,
    name: *const c_char,
    dataType: ANARIDataType,
    mem: *const c_void,
) {
    ops::set_parameter(device, object, name, dataType, mem)
}

#[no_mangle]
pub unsafe extern "C" fn anariUnsetParameter(
    device: ANARIDevice,
    object: ANARIObject,
    name: *const c_char,
) {
    ops::unset_parameter(device, object, name)
}

#[no_mangle]
pub unsafe extern "C" fn anariUnsetAllParameters(device: ANARIDevice, object: ANARIObject) {
    ops::unset_all_parameters(device, object)
}

#[no_mangle]
pub unsafe extern "C" fn anariMapParameterArray1D(
    device: ANARIDevice,
    object: ANARIObject,
    name: *const c_char,
    dataType: ANARIDataType,
    numElements1: u64,
    elementStride: *mut u64,
) -> *mut c_void {
    ops::map_parameter_array_1d(device, object, name, dataType, numElements1, elementStride)
}

#[no_mangle]
pub unsafe extern "C" fn anariMapParameterArray2D(
    device: ANARIDevice,
    object: ANARIObject,
    name: *const c_char,
    dataType: ANARIDataType,
    numElements1: u64,
    numElements2: u64,
    elementStride: *mut u64,
) -> *mut c_void {
    ops::map_parameter_array_2d(
        device,
        object,
        name,
        dataType,
        numElements1,
        numElements2,
        elementStride,
    )
}

#[no_mangle]
pub unsafe extern "C" fn anariMapParameterArray3D(
    device: ANARIDevice,
    object: ANARIObject,
    name: *const c_char,
    dataType: ANARIDataType,
    numElements1: u64,
    numElements2: u64,
    numElements3: u64,
    elementStride: *mut u64,
) -> *mut c_void {
    ops::map_parameter_array_3d(
        device,
        object,
        name,
        dataType,
        numElements1,
        numElements2,
        numElements3,
        elementStride,
    )
}

#[no_mangle]
pub unsafe extern "C" fn anariUnmapParameterArray(
    device: ANARIDevice,
    object: ANARIObject,
    name: *const c_char,
) {
    ops::unmap_parameter_array(device, object, name)
}

#[no_mangle]
pub unsafe extern "C" fn anariCommitParameters(device: ANARIDevice, object: ANARIObject) {
    ops::commit_parameters(device, object)
}

#[no_mangle]
pub unsafe extern "C" fn anariGetObjectSubtypes(
    device: ANARIDevice,
    objectType: ANARIDataType,
) -> *mut *const c_char {
    ops::get_object_subtypes(device, objectType)
}

#[no_mangle]
pub unsafe extern "C" fn anariGetObjectInfo(
    device: ANARIDevice,
    objectType: ANARIDataType,
    objectSubtype: *const c_char,
    infoName: *const c_char,
    infoType: ANARIDataType,
) -> *const c_void {
    ops::get_object_info(device, objectType, objectSubtype, infoName, infoType)
}

#[no_mangle]
pub unsafe extern "C" fn anariGetParameterInfo(
    device: ANARIDevice,
    objectType: ANARIDataType,
    objectSubtype: *const c_char,
    parameterName: *const c_char,
    parameterType: ANARIDataType,
    infoName: *const c_char,
    infoType: ANARIDataType,
) -> *const c_void {
    ops::get_parameter_info(
        device,
        objectType,
        objectSubtype,
        parameterName,
        parameterType,
        infoName,
        infoType,
    )
}

#[no_mangle]
pub unsafe extern "C" fn anariGetProperty(
    device: ANARIDevice,
    object: ANARIObject,
    name: *const c_char,
    dataType: ANARIDataType,
    mem: *mut c_void,
    size: u64,
    mask: ANARIWaitMask,
) -> c_int {
    ops::get_property(device, object, name, dataType, mem, size, mask)
}

#[no_mangle]
pub unsafe extern "C" fn anariRenderFrame(device: ANARIDevice, frame: ANARIFrame) {
    ops::render_frame(device, frame)
}

#[no_mangle]
pub unsafe extern "C" fn anariFrameReady(
    device: ANARIDevice,
    frame: ANARIFrame,
    mask: ANARIWaitMask,
) -> c_int {
    ops::frame_ready(device, frame, mask)
}

#[no_mangle]
pub unsafe extern "C" fn anariDiscardFrame(device: ANARIDevice, frame: ANARIFrame) {
    ops::discard_frame(device, frame)
}

#[no_mangle]
pub unsafe extern "C" fn anariMapFrame(
    device: ANARIDevice,
    frame: ANARIFrame,
    channel: *const c_char,
    width: *mut u32,
    height: *mut u32,
    pixelType: *mut ANARIDataType,
) -> *const c_void {
    ops::map_frame(device, frame, channel, width, height, pixelType)
}

#[no_mangle]
pub unsafe extern "C" fn anariUnmapFrame(
    device: ANARIDevice,
    frame: ANARIFrame,
    channel: *const c_char,
) {
    ops::unmap_frame(device, frame, channel)
}

#[no_mangle]
pub unsafe extern "C" fn caverayPinholeFromScreen(
    lowerLeft: *const f32,
    lowerRight: *const f32,
    upperRight: *const f32,
    eye: *const f32,
    out: *mut CaverayPinhole,
) -> ANARIStatusCode {
    helpers::pinhole_from_screen(lowerLeft, lowerRight, upperRight, eye, out)
}

#[no_mangle]
pub unsafe extern "C" fn caverayPinholeFromMatrices(
    view: *const f32,
    proj: *const f32,
    out: *mut CaverayPinhole,
) -> ANARIStatusCode {
    helpers::pinhole_from_matrices(view, proj, out)
}

#[no_mangle]
pub unsafe extern "C" fn caverayMatricesFromScreen(
    lowerLeft: *const f32,
    lowerRight: *const f32,
    upperRight: *const f32,
    eye: *const f32,
    nearClip: f32,
    farClip: f32,
    view: *mut f32,
    proj: *mut f32,
) -> ANARIStatusCode {
    helpers::matrices_from_screen(
        lowerLeft, lowerRight, upperRight, eye, nearClip, farClip, view, proj,
    )
}

#[no_mangle]
pub unsafe extern "C" fn caverayLastError() -> *const c_char {
    helpers::last_error()
}

/// What `anariLoadLibrary` in the SDK's libanari looks up after dlopen.
#[no_mangle]
pub unsafe extern "C" fn anari_library_caveray_new_library(
    dl_handle: *mut c_void,
    status_callback: ANARIStatusCallback,
    status_user: *const c_void,
) -> *mut c_void {
    ops::new_library(dl_handle, status_callback, status_user)
}

/// Never called: it only has to compile. Each export and bindgen's
/// declaration of the same name must unify to one function type.
#[allow(dead_code, clippy::fn_to_numeric_cast_any)]
fn exports_match_the_headers() {
    use super::sys;
    fn same<F>(_: F, _: F) {}
    same(
        sys::anariLoadLibrary as unsafe extern "C" fn(_, _, _) -> _,
        anariLoadLibrary as unsafe extern "C" fn(_, _, _) -> _,
    );
    same(
        sys::anariUnloadLibrary as unsafe extern "C" fn(_) -> _,
        anariUnloadLibrary as unsafe extern "C" fn(_) -> _,
    );
    same(
        sys::anariLoadModule as unsafe extern "C" fn(_, _) -> _,
        anariLoadModule as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariUnloadModule as unsafe extern "C" fn(_, _) -> _,
        anariUnloadModule as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewDevice as unsafe extern "C" fn(_, _) -> _,
        anariNewDevice as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewInitializedDevice as unsafe extern "C" fn(_, _, _) -> _,
        anariNewInitializedDevice as unsafe extern "C" fn(_, _, _) -> _,
    );
    same(
        sys::anariGetDeviceSubtypes as unsafe extern "C" fn(_) -> _,
        anariGetDeviceSubtypes as unsafe extern "C" fn(_) -> _,
    );
    same(
        sys::anariGetDeviceExtensions as unsafe extern "C" fn(_, _) -> _,
        anariGetDeviceExtensions as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewArray1D as unsafe extern "C" fn(_, _, _, _, _, _) -> _,
        anariNewArray1D as unsafe extern "C" fn(_, _, _, _, _, _) -> _,
    );
    same(
        sys::anariNewArray2D as unsafe extern "C" fn(_, _, _, _, _, _, _) -> _,
        anariNewArray2D as unsafe extern "C" fn(_, _, _, _, _, _, _) -> _,
    );
    same(
        sys::anariNewArray3D as unsafe extern "C" fn(_, _, _, _, _, _, _, _) -> _,
        anariNewArray3D as unsafe extern "C" fn(_, _, _, _, _, _, _, _) -> _,
    );
    same(
        sys::anariMapArray as unsafe extern "C" fn(_, _) -> _,
        anariMapArray as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariUnmapArray as unsafe extern "C" fn(_, _) -> _,
        anariUnmapArray as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewLight as unsafe extern "C" fn(_, _) -> _,
        anariNewLight as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewCamera as unsafe extern "C" fn(_, _) -> _,
        anariNewCamera as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewGeometry as unsafe extern "C" fn(_, _) -> _,
        anariNewGeometry as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewSpatialField as unsafe extern "C" fn(_, _) -> _,
        anariNewSpatialField as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewVolume as unsafe extern "C" fn(_, _) -> _,
        anariNewVolume as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewMaterial as unsafe extern "C" fn(_, _) -> _,
        anariNewMaterial as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewSampler as unsafe extern "C" fn(_, _) -> _,
        anariNewSampler as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewInstance as unsafe extern "C" fn(_, _) -> _,
        anariNewInstance as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewRenderer as unsafe extern "C" fn(_, _) -> _,
        anariNewRenderer as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariNewSurface as unsafe extern "C" fn(_) -> _,
        anariNewSurface as unsafe extern "C" fn(_) -> _,
    );
    same(
        sys::anariNewGroup as unsafe extern "C" fn(_) -> _,
        anariNewGroup as unsafe extern "C" fn(_) -> _,
    );
    same(
        sys::anariNewWorld as unsafe extern "C" fn(_) -> _,
        anariNewWorld as unsafe extern "C" fn(_) -> _,
    );
    same(
        sys::anariNewFrame as unsafe extern "C" fn(_) -> _,
        anariNewFrame as unsafe extern "C" fn(_) -> _,
    );
    same(
        sys::anariNewObject as unsafe extern "C" fn(_, _, _) -> _,
        anariNewObject as unsafe extern "C" fn(_, _, _) -> _,
    );
    same(
        sys::anariRelease as unsafe extern "C" fn(_, _) -> _,
        anariRelease as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariRetain as unsafe extern "C" fn(_, _) -> _,
        anariRetain as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariSetParameter as unsafe extern "C" fn(_, _, _, _, _) -> _,
        anariSetParameter as unsafe extern "C" fn(_, _, _, _, _) -> _,
    );
    same(
        sys::anariUnsetParameter as unsafe extern "C" fn(_, _, _) -> _,
        anariUnsetParameter as unsafe extern "C" fn(_, _, _) -> _,
    );
    same(
        sys::anariUnsetAllParameters as unsafe extern "C" fn(_, _) -> _,
        anariUnsetAllParameters as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariMapParameterArray1D as unsafe extern "C" fn(_, _, _, _, _, _) -> _,
        anariMapParameterArray1D as unsafe extern "C" fn(_, _, _, _, _, _) -> _,
    );
    same(
        sys::anariMapParameterArray2D as unsafe extern "C" fn(_, _, _, _, _, _, _) -> _,
        anariMapParameterArray2D as unsafe extern "C" fn(_, _, _, _, _, _, _) -> _,
    );
    same(
        sys::anariMapParameterArray3D as unsafe extern "C" fn(_, _, _, _, _, _, _, _) -> _,
        anariMapParameterArray3D as unsafe extern "C" fn(_, _, _, _, _, _, _, _) -> _,
    );
    same(
        sys::anariUnmapParameterArray as unsafe extern "C" fn(_, _, _) -> _,
        anariUnmapParameterArray as unsafe extern "C" fn(_, _, _) -> _,
    );
    same(
        sys::anariCommitParameters as unsafe extern "C" fn(_, _) -> _,
        anariCommitParameters as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariGetObjectSubtypes as unsafe extern "C" fn(_, _) -> _,
        anariGetObjectSubtypes as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariGetObjectInfo as unsafe extern "C" fn(_, _, _, _, _) -> _,
        anariGetObjectInfo as unsafe extern "C" fn(_, _, _, _, _) -> _,
    );
    same(
        sys::anariGetParameterInfo as unsafe extern "C" fn(_, _, _, _, _, _, _) -> _,
        anariGetParameterInfo as unsafe extern "C" fn(_, _, _, _, _, _, _) -> _,
    );
    same(
        sys::anariGetProperty as unsafe extern "C" fn(_, _, _, _, _, _, _) -> _,
        anariGetProperty as unsafe extern "C" fn(_, _, _, _, _, _, _) -> _,
    );
    same(
        sys::anariRenderFrame as unsafe extern "C" fn(_, _) -> _,
        anariRenderFrame as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariFrameReady as unsafe extern "C" fn(_, _, _) -> _,
        anariFrameReady as unsafe extern "C" fn(_, _, _) -> _,
    );
    same(
        sys::anariDiscardFrame as unsafe extern "C" fn(_, _) -> _,
        anariDiscardFrame as unsafe extern "C" fn(_, _) -> _,
    );
    same(
        sys::anariMapFrame as unsafe extern "C" fn(_, _, _, _, _, _) -> _,
        anariMapFrame as unsafe extern "C" fn(_, _, _, _, _, _) -> _,
    );
    same(
        sys::anariUnmapFrame as unsafe extern "C" fn(_, _, _) -> _,
        anariUnmapFrame as unsafe extern "C" fn(_, _, _) -> _,
    );
    same(
        sys::caverayPinholeFromScreen as unsafe extern "C" fn(_, _, _, _, _) -> _,
        caverayPinholeFromScreen as unsafe extern "C" fn(_, _, _, _, _) -> _,
    );
    same(
        sys::caverayPinholeFromMatrices as unsafe extern "C" fn(_, _, _) -> _,
        caverayPinholeFromMatrices as unsafe extern "C" fn(_, _, _) -> _,
    );
    same(
        sys::caverayMatricesFromScreen as unsafe extern "C" fn(_, _, _, _, _, _, _, _) -> _,
        caverayMatricesFromScreen as unsafe extern "C" fn(_, _, _, _, _, _, _, _) -> _,
    );
    same(
        sys::caverayLastError as unsafe extern "C" fn() -> _,
        caverayLastError as unsafe extern "C" fn() -> _,
    );
}
