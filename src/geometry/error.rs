use thiserror::Error;

use super::Rounded;

/// Why a wall, eye or matrix pair cannot define a camera.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum GeometryError {
    #[error("{what} is not finite (NaN or infinity)")]
    NonFinite { what: &'static str },
    #[error("wall has zero area: width {}, height {}", Rounded(*.width), Rounded(*.height))]
    ZeroAreaWall { width: f64, height: f64 },
    #[error(
        "wall is not a rectangle: edges LL-LR and LR-UR meet at {} degrees, not 90",
        Rounded(*.angle_deg)
    )]
    NotRectangular { angle_deg: f64 },
    #[error(
        "wall is not a planar rectangle: UL is {} away from LL + (UR - LR)",
        Rounded(*.distance)
    )]
    NotPlanar { distance: f64 },
    #[error(
        "eye is on or behind the wall: its distance along the wall normal is {} (must be > 0)",
        Rounded(*.d)
    )]
    EyeBehindWall { d: f64 },
    #[error(
        "clip planes must satisfy 0 < near < far (near {}, far {})",
        Rounded(*.near),
        Rounded(*.far)
    )]
    NearFar { near: f64, far: f64 },
    #[error("view-projection matrix is singular (determinant {})", Rounded(*.det))]
    SingularMatrix { det: f64 },
    #[error("projection is not a perspective frustum: {reason}")]
    NonPerspective { reason: String },
    #[error("{which} frustum planes are parallel, so no eye can be recovered (orthographic projection?)")]
    ParallelPlanes { which: &'static str },
    #[error("invalid pinhole camera: {reason}")]
    InvalidPinhole { reason: String },
}

pub(crate) fn check_finite(what: &'static str, values: &[f64]) -> Result<(), GeometryError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(GeometryError::NonFinite { what })
    }
}
