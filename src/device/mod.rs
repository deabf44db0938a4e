//! The ANARI object model in plain Rust: objects behind handles,
//! parameters set and committed, arrays, cameras, frames and the render
//! thread. The C layer (`crate::capi`) converts and forwards to this.

mod api;
mod array;
mod camera;
mod commit;
mod frame;
mod frames;
pub mod info;
mod object;
mod transfer_function;
mod types;
mod value;
mod volume;
mod worker;

pub use api::{Device, Input, Property, Target};
pub use array::{Array, HostMemory};
pub use camera::CameraModel;
pub use frame::FrameSlot;
pub use frames::Mapped;
pub use transfer_function::{TransferFunction, TransferFunctionError, TABLE_SIZE};
pub use types::{kind_name, DataType, Severity, Status, StatusCode};
pub use value::{Params, Value};
pub use volume::{StructuredVolume, VolumeError, Voxels};
pub use worker::{panic_message, BackendChoice, Reporter};
