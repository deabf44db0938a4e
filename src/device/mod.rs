//! The ANARI object model in plain Rust: objects behind handles,
//! parameters set and committed, arrays and frames. Each implemented
//! subtype is a module of its own (a folder per object kind, helide-style)
//! holding its parameter table and its commit; `info` lists them. When a
//! frame renders, `snapshot` reads its objects (through the typed
//! accessors of `access`, the one place that looks inside an object's
//! state) into plain values, which `crate::engine` renders. The C layer
//! (`crate::capi`) converts and forwards to this.

mod access;
mod array;
mod calls;
pub mod camera;
mod device_object;
mod elements;
pub mod frame;
mod geometry;
mod group;
pub mod info;
mod instance;
mod light;
mod material;
mod object;
pub mod table;

mod renderer;
mod sampler;
mod snapshot;
mod spatial_field;
mod surface;
mod types;

pub mod volume;
mod world;

pub use crate::engine::{panic_message, FrameSlot};
pub use array::{Array, HostMemory};
pub use calls::{Device, Input, Mapped, OnDone, Property, Subject};
pub use camera::CameraModel;
pub use object::{Params, Value};
pub use types::{kind_name, object_kind, DataType, Reporter, Severity, Status, StatusCode};
