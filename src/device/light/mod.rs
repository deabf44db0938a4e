//! Lights: one module per subtype. caveray's shading has one parallel
//! light; the first directional light of a world sets it.

pub mod directional;

pub use directional::DirectionalLight;
