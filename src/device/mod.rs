//! The scene objects a renderer consumes, in plain Rust: structured regular
//! volumes and 1D transfer functions. The C layer will wrap these.

mod transfer_function;
mod volume;

pub use transfer_function::{TransferFunction, TransferFunctionError, TABLE_SIZE};
pub use volume::{StructuredVolume, VolumeError, Voxels};
