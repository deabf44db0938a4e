//! Instances: one module per subtype.

pub mod transform;

pub use transform::InstanceModel;
