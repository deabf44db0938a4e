//! Spatial fields: one module per subtype.

pub mod structured_regular;
pub mod unstructured;
