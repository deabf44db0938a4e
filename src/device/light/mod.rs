//! Lights: one module per subtype (point and spot share one). caveray's
//! volume shading has one parallel light; the first directional light of
//! a world sets it. Surfaces take it and up to 8 point and spot lights.

pub mod directional;
pub mod point;

pub use directional::DirectionalLight;
