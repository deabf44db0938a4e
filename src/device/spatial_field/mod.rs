//! Spatial fields: one module per subtype.

pub mod amr;
pub mod structured_regular;
pub mod unstructured;
