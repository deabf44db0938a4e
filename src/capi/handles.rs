//! The library and device objects behind `ANARILibrary` and `ANARIDevice`.
//! Their first fields have the C++ layout the ANARI SDK loader expects
//! (Itanium ABI: a table pointer, then the base class's data members), so
//! the loader can call them virtually; everything after is ours.

use std::collections::HashSet;
use std::ffi::c_void;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use super::gate::{teardown, HostGate};
use super::status::{emit, Callback};
use super::sys;
use crate::device::{Device, Reporter, Status};

/// `{vtable*, dlhandle, statusCB, statusUserPtr}`: 32 bytes.
#[repr(C)]
pub struct LibraryHandle {
    table: *const c_void,
    pub dl_handle: *mut c_void,
    pub status: sys::ANARIStatusCallback,
    pub status_user: *const c_void,
}

/// `{vtable*, statusCB, statusUserPtr}` (24 bytes), then our state.
#[repr(C)]
pub struct DeviceHandle {
    table: *const c_void,
    pub default_status: sys::ANARIStatusCallback,
    pub default_status_user: *const c_void,
    refs: AtomicU32,
    device: Mutex<Device>,
    /// The callback in effect: the device's committed `statusCallback`, or
    /// the library's. Shared with the render thread.
    callback: Arc<Mutex<Callback>>,
    /// What every call into the host passes; closed by the last release.
    pub gate: Arc<HostGate>,
}

// The raw pointers are the host's opaque values, only handed back to it.
unsafe impl Send for DeviceHandle {}
unsafe impl Sync for DeviceHandle {}

/// The loader tables a new handle points at. `entry_points` owns them and
/// hands them down, so this file needs nothing of it.
#[derive(Clone, Copy)]
pub struct Tables {
    pub library: *const c_void,
    pub device: *const c_void,
}

/// Live libraries and devices, so that a stale or foreign pointer is
/// reported instead of dereferenced.
static LIBRARIES: Mutex<Option<HashSet<usize>>> = Mutex::new(None);
static DEVICES: Mutex<Option<HashSet<usize>>> = Mutex::new(None);

fn registry(set: &Mutex<Option<HashSet<usize>>>) -> MutexGuard<'_, Option<HashSet<usize>>> {
    set.lock().unwrap_or_else(|e| e.into_inner())
}

impl LibraryHandle {
    pub fn create(tables: Tables, dl_handle: *mut c_void, cb: Callback) -> *mut LibraryHandle {
        let lib = Box::into_raw(Box::new(LibraryHandle {
            table: tables.library,
            dl_handle,
            status: cb.function,
            status_user: cb.user as *const c_void,
        }));
        registry(&LIBRARIES)
            .get_or_insert_with(HashSet::new)
            .insert(lib as usize);
        lib
    }

    /// The library behind `ptr` if it is one of ours and alive.
    pub fn get<'a>(ptr: sys::ANARILibrary) -> Option<&'a LibraryHandle> {
        let live = registry(&LIBRARIES)
            .as_ref()
            .is_some_and(|s| s.contains(&(ptr as usize)));
        // SAFETY: registered pointers are live boxes until `destroy`.
        live.then(|| unsafe { &*(ptr as *const LibraryHandle) })
    }

    pub fn callback(&self) -> Callback {
        Callback {
            function: self.status,
            user: self.status_user as usize,
        }
    }

    /// Frees the library; false if `ptr` is not a live library.
    pub fn destroy(ptr: sys::ANARILibrary) -> bool {
        let removed = registry(&LIBRARIES)
            .as_mut()
            .is_some_and(|s| s.remove(&(ptr as usize)));
        if removed {
            // SAFETY: it was created by `Box::into_raw` and is now unregistered.
            drop(unsafe { Box::from_raw(ptr as *mut LibraryHandle) });
        }
        removed
    }
}

impl DeviceHandle {
    pub fn create(tables: Tables, library_callback: Callback) -> *mut DeviceHandle {
        let callback = Arc::new(Mutex::new(library_callback));
        let gate = Arc::new(HostGate::default());
        let handle = Box::into_raw(Box::new_uninit());
        let reporter: Reporter = {
            let (callback, gate) = (callback.clone(), gate.clone());
            let device = handle as usize;
            Arc::new(move |s: Status| {
                let cb = *callback.lock().unwrap_or_else(|e| e.into_inner());
                gate.call(|| emit(cb, device as *mut c_void, &s));
            })
        };
        // SAFETY: `handle` is a fresh allocation of the right layout.
        unsafe {
            (*handle).write(DeviceHandle {
                table: tables.device,
                default_status: library_callback.function,
                default_status_user: library_callback.user as *const c_void,
                refs: AtomicU32::new(1),
                device: Mutex::new(Device::new(reporter)),
                callback,
                gate,
            });
        }
        let handle = handle as *mut DeviceHandle;
        registry(&DEVICES)
            .get_or_insert_with(HashSet::new)
            .insert(handle as usize);
        handle
    }

    /// The device behind `ptr` with one more temporary reference, if it is
    /// one of ours and alive.
    pub fn get(ptr: sys::ANARIDevice) -> Option<DeviceRef> {
        let reg = registry(&DEVICES);
        if !reg.as_ref().is_some_and(|s| s.contains(&(ptr as usize))) {
            return None;
        }
        // SAFETY: registered pointers are live; the reference taken while
        // the registry is locked keeps it so until `DeviceRef` drops.
        let handle = unsafe { &*(ptr as *const DeviceHandle) };
        handle.refs.fetch_add(1, Ordering::AcqRel);
        Some(DeviceRef(ptr as *mut DeviceHandle))
    }

    pub fn lock(&self) -> MutexGuard<'_, Device> {
        self.device.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub fn callback(&self) -> Callback {
        *self.callback.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub fn set_callback(&self, cb: Callback) {
        *self.callback.lock().unwrap_or_else(|e| e.into_inner()) = cb;
    }

    pub fn default_callback(&self) -> Callback {
        Callback {
            function: self.default_status,
            user: self.default_status_user as usize,
        }
    }

    pub fn retain(&self) {
        self.refs.fetch_add(1, Ordering::AcqRel);
    }

    /// Drops one reference. The last one hands the device to a teardown
    /// thread, which stops its renders and frees it, and then closes the
    /// device's way back to the host (gate.rs): what the stopped renders
    /// had to say within the release's wait is still heard.
    pub fn release(ptr: *mut DeviceHandle) {
        let mut reg = registry(&DEVICES);
        // SAFETY: callers hold a reference, so the box is alive.
        let last = unsafe { &*ptr }.refs.fetch_sub(1, Ordering::AcqRel) == 1;
        if last {
            if let Some(s) = reg.as_mut() {
                s.remove(&(ptr as usize));
            }
            drop(reg);
            // SAFETY: the last reference is gone and the pointer unregistered.
            let handle = unsafe { Box::from_raw(ptr) };
            let gate = Arc::clone(&handle.gate);
            teardown(handle);
            gate.close();
        }
    }
}

/// A counted reference to a live device for the length of one call, so a
/// host releasing the device from another thread cannot free it under us.
pub struct DeviceRef(*mut DeviceHandle);

impl DeviceRef {
    pub fn ptr(&self) -> *mut c_void {
        self.0.cast()
    }
}

impl std::ops::Deref for DeviceRef {
    type Target = DeviceHandle;
    fn deref(&self) -> &DeviceHandle {
        // SAFETY: the reference counted in `get` keeps the box alive.
        unsafe { &*self.0 }
    }
}

impl Drop for DeviceRef {
    fn drop(&mut self) {
        DeviceHandle::release(self.0);
    }
}

// Where libanari reads the C++ data members: the library's dlhandle, status
// callback and user pointer, and the device's default status callback and
// user pointer, each right after the table pointer.
const _: () = {
    use std::mem::{offset_of, size_of};
    assert!(size_of::<LibraryHandle>() == 32);
    assert!(offset_of!(LibraryHandle, dl_handle) == 8);
    assert!(offset_of!(LibraryHandle, status) == 16);
    assert!(offset_of!(LibraryHandle, status_user) == 24);
    assert!(offset_of!(DeviceHandle, table) == 0);
    assert!(offset_of!(DeviceHandle, default_status) == 8);
    assert!(offset_of!(DeviceHandle, default_status_user) == 16);
};
