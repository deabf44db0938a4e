//! What the engine tells the host: severities and codes as ANARI numbers
//! them, and the object a message is about. The device turns a note into
//! its status (with the object's ANARI type) and hands it on.

use std::sync::Arc;

/// ANARI's status severities.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    FatalError = 1,
    Error = 2,
    Warning = 3,
    PerformanceWarning = 4,
    Info = 5,
    Debug = 6,
}

/// ANARI's status codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StatusCode {
    NoError = 0,
    UnknownError = 1,
    InvalidArgument = 2,
    InvalidOperation = 3,
    OutOfMemory = 4,
    UnsupportedDevice = 5,
    VersionMismatch = 6,
}

/// What a note is about: the device as a whole, or one frame (its handle).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum About {
    Device,
    Frame(u64),
}

/// One message from the engine's threads.
#[derive(Clone, Debug, PartialEq)]
pub struct Note {
    pub severity: Severity,
    pub code: StatusCode,
    pub about: About,
    pub message: String,
}

impl Note {
    /// A message about frame `frame` that is no error.
    pub fn frame(severity: Severity, frame: u64, message: String) -> Self {
        Self {
            severity,
            code: StatusCode::NoError,
            about: About::Frame(frame),
            message,
        }
    }
}

/// Where the engine's notes go; called from any of its threads.
pub type Notify = Arc<dyn Fn(Note) + Send + Sync>;

/// The text a panic carried, for the message that reports it.
pub fn panic_message(panic: &Box<dyn std::any::Any + Send>) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}
