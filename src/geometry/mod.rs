//! Off-axis camera mathematics for walls in any orientation.
//!
//! A wall ([`Screen`]) and a tracked eye define a generalized perspective
//! projection. CAVE hosts can hand us that view in three ways (Zellmann &
//! Amstutz): as OpenGL matrices ([`MatrixCamera`], strategy 1), as a pinhole
//! camera with an image region ([`PinholeCamera::from_screen`], strategy 2),
//! or as matrices from which a pinhole is recovered
//! ([`pinhole_from_matrices`], strategy 3). [`OffAxisCamera`] takes the wall
//! and eye directly. Every camera implements [`PrimaryRays`] and lowers to
//! the same [`RayGen`] value, so a renderer never knows which one it got.

mod axis;
mod display;
mod error;
mod from_matrices;
mod matrix_camera;
mod off_axis;
mod orthographic;
mod pinhole;
mod projection;
mod ray;
mod rounded;
mod screen;
mod slab;
mod units;

#[cfg(test)]
mod tests;

pub use axis::VolumeAxis;
pub use display::{
    MultiViewDisplay, PanelNumber, ViewPattern, EYES_IN_PANEL_WIDTHS, MAX_SLANT, MAX_VIEWS,
    PITCH_RANGE,
};
pub use error::GeometryError;
pub use from_matrices::{pinhole_from_matrices, RecoveredPinhole};
pub use matrix_camera::MatrixCamera;
pub use off_axis::OffAxisCamera;
pub use orthographic::OrthographicCamera;
pub use pinhole::{ImageRegion, PinholeCamera};
pub use projection::{frustum, OffAxisProjection};
pub use ray::{pixel_centre, PrimaryRays, Ray, RayGen};
pub use rounded::Rounded;
pub use screen::{Screen, WallExtents};
pub use slab::enter_exit;
pub use units::Units;

pub type Result<T> = std::result::Result<T, GeometryError>;
