//! Getting messages to the host: the status callback of the device (or of
//! the library it came from), and the guard that keeps panics on our side
//! of the C boundary.

use std::ffi::{c_void, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;

use super::sys;
use crate::device::{panic_message, DataType, Severity, Status, StatusCode};

/// A status callback and its user pointer, as plain values.
#[derive(Clone, Copy)]
pub struct Callback {
    pub function: sys::ANARIStatusCallback,
    pub user: usize,
}

impl Callback {
    pub const NONE: Self = Self {
        function: None,
        user: 0,
    };
}

/// The callback of the most recently loaded library: where messages go
/// when a call names no usable device (NULL or released handles).
static LIBRARY_CALLBACK: Mutex<Callback> = Mutex::new(Callback::NONE);

pub fn set_library_callback(cb: Callback) {
    *LIBRARY_CALLBACK.lock().unwrap_or_else(|e| e.into_inner()) = cb;
}

pub fn library_callback() -> Callback {
    *LIBRARY_CALLBACK.lock().unwrap_or_else(|e| e.into_inner())
}

/// Sends `status` to `cb`; with no callback, errors and warnings go to
/// stderr so that a host that registered nothing still sees them.
pub fn emit(cb: Callback, device: *mut c_void, status: &Status) {
    let source = if status.source == 0 {
        device
    } else {
        status.source as usize as *mut c_void
    };
    match cb.function {
        Some(f) => {
            let message = CString::new(status.message.replace('\0', " ")).unwrap_or_default();
            // SAFETY: the host registered this function for exactly these
            // arguments; the message outlives the call.
            unsafe {
                f(
                    cb.user as *const c_void,
                    device,
                    source,
                    status.source_kind as i32,
                    status.severity as i32,
                    status.code as i32,
                    message.as_ptr(),
                )
            }
        }
        None if (status.severity as i32) <= Severity::Warning as i32 => {
            eprintln!("caveray: {:?}: {}", status.severity, status.message);
        }
        None => {}
    }
}

/// An error about the call itself, not about any device's object.
pub fn call_error(code: StatusCode, message: String) {
    emit(
        library_callback(),
        std::ptr::null_mut(),
        &Status {
            severity: Severity::Error,
            code,
            source: 0,
            source_kind: DataType::UNKNOWN,
            message,
        },
    );
}

/// Runs `f`, turning a panic into an error message and `neutral`, so no
/// unwinding ever crosses into the host.
pub fn guard<R>(call: &str, neutral: R, f: impl FnOnce() -> R) -> R {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(panic) => {
            let message = format!(
                "{call}: internal error ({}); the call was ignored",
                panic_message(&panic)
            );
            // Reporting must not panic again; if it does, stay silent.
            let _ = catch_unwind(AssertUnwindSafe(|| {
                call_error(StatusCode::UnknownError, message)
            }));
            neutral
        }
    }
}
