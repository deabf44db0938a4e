//! The ANARI object model in plain Rust: objects behind handles,
//! parameters set and committed, arrays, frames and the render thread.
//! Each implemented subtype is a module of its own (a folder per object
//! kind, helide-style) holding its parameter table and its commit; `info`
//! lists them. The C layer (`crate::capi`) converts and forwards to this.

mod array;
mod calls;
pub mod camera;
mod device_object;
pub mod frame;
mod geometry;
mod group;
pub mod info;
mod instance;
mod light;
mod material;
mod object;
mod read;
mod renderer;
mod spatial_field;
mod surface;
mod types;
mod value;
pub mod volume;
mod worker;
mod world;

pub use array::{Array, HostMemory};
pub use calls::{Device, Input, Mapped, Property, Subject};
pub use camera::CameraModel;
pub use frame::slot::FrameSlot;
pub use types::{kind_name, object_kind, DataType, Severity, Status, StatusCode};
pub use value::{Params, Value};
pub use worker::{panic_message, Reporter};
