//! Volumes: one module per subtype.

pub mod transfer_function_1d;

pub use transfer_function_1d::VolumeModel;
