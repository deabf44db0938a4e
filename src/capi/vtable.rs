//! The tables of function pointers the ANARI SDK loader calls through.
//!
//! libanari treats our library and device handles as C++ objects of its
//! `LibraryImpl` / `DeviceImpl` classes: on Linux x86-64 (Itanium C++ ABI)
//! the object starts with a pointer to the class's virtual table, and a
//! virtual call passes the object as the first argument, like a C
//! function. Slot order is that of SDK 0.14 and later (ANARI_FACTS.md).
//! Each slot points at the same function the exported C symbol uses.

use std::ffi::c_void;

use super::ops;

/// One virtual table: pointers to `extern "C"` functions, in slot order.
#[repr(transparent)]
pub struct Table<const N: usize>([*const c_void; N]);

// SAFETY: the tables are immutable function addresses.
unsafe impl<const N: usize> Sync for Table<N> {}

pub type LibraryTable = Table<8>;
pub type DeviceTable = Table<41>;

pub static LIBRARY_TABLE: LibraryTable = Table([
    ops::library_complete_destructor as *const c_void, // 0 complete destructor
    ops::unload_library as *const c_void,              // 1 deleting destructor
    ops::new_device as *const c_void,                  // 2 newDevice
    ops::new_initialized_device as *const c_void,      // 3 newInitializedDevice
    ops::get_device_extensions as *const c_void,       // 4 getDeviceExtensions
    ops::get_device_subtypes as *const c_void,         // 5 getDeviceSubtypes
    ops::load_module as *const c_void,                 // 6 loadModule
    ops::unload_module as *const c_void,               // 7 unloadModule
]);

pub static DEVICE_TABLE: DeviceTable = Table([
    ops::new_array_1d as *const c_void,           // 0
    ops::new_array_2d as *const c_void,           // 1
    ops::new_array_3d as *const c_void,           // 2
    ops::new_geometry as *const c_void,           // 3
    ops::new_material as *const c_void,           // 4
    ops::new_sampler as *const c_void,            // 5
    ops::new_surface as *const c_void,            // 6
    ops::new_spatial_field as *const c_void,      // 7
    ops::new_volume as *const c_void,             // 8
    ops::new_light as *const c_void,              // 9
    ops::new_group as *const c_void,              // 10
    ops::new_instance as *const c_void,           // 11
    ops::new_world as *const c_void,              // 12
    ops::new_camera as *const c_void,             // 13
    ops::new_renderer as *const c_void,           // 14
    ops::new_frame as *const c_void,              // 15
    ops::set_parameter as *const c_void,          // 16
    ops::unset_parameter as *const c_void,        // 17
    ops::unset_all_parameters as *const c_void,   // 18
    ops::map_parameter_array_1d as *const c_void, // 19
    ops::map_parameter_array_2d as *const c_void, // 20
    ops::map_parameter_array_3d as *const c_void, // 21
    ops::unmap_parameter_array as *const c_void,  // 22
    ops::commit_parameters as *const c_void,      // 23
    ops::release as *const c_void,                // 24 (also the device itself)
    ops::retain as *const c_void,                 // 25
    ops::map_array as *const c_void,              // 26
    ops::unmap_array as *const c_void,            // 27
    ops::get_property as *const c_void,           // 28
    ops::get_object_subtypes as *const c_void,    // 29
    ops::get_object_info as *const c_void,        // 30
    ops::get_parameter_info as *const c_void,     // 31
    ops::map_frame as *const c_void,              // 32 frameBufferMap
    ops::unmap_frame as *const c_void,            // 33 frameBufferUnmap
    ops::render_frame as *const c_void,           // 34
    ops::frame_ready as *const c_void,            // 35
    ops::discard_frame as *const c_void,          // 36
    ops::new_object as *const c_void,             // 37
    ops::get_proc_address as *const c_void,       // 38
    ops::device_destructor as *const c_void,      // 39 complete destructor
    ops::device_destructor as *const c_void,      // 40 deleting destructor
]);
