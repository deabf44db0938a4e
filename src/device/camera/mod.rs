//! Cameras: one module per subtype, each lowering to the renderer's
//! `RayGen` for a frame through `CameraModel`.

pub mod matrix;
pub mod off_axis;
pub mod perspective;

use glam::{DVec3, UVec2};

use super::object::{Derived, State};
use crate::geometry::{
    ImageRegion, MatrixCamera, OffAxisCamera, PinholeCamera, PrimaryRays, RayGen,
};

#[derive(Clone, Debug)]
pub enum CameraModel {
    /// ANARI's perspective camera; `aspect` falls back to the frame's.
    Perspective {
        position: DVec3,
        direction: DVec3,
        up: DVec3,
        fovy: f64,
        aspect: Option<f64>,
        region: ImageRegion,
    },
    Matrix(Box<MatrixCamera>),
    OffAxis(OffAxisCamera),
}

impl CameraModel {
    pub fn ray_gen(&self, size: UVec2) -> Result<RayGen, String> {
        match self {
            CameraModel::Perspective {
                position,
                direction,
                up,
                fovy,
                aspect,
                region,
            } => {
                let aspect = aspect.unwrap_or(f64::from(size.x) / f64::from(size.y));
                PinholeCamera::new(*position, *direction, *up, *fovy, aspect, *region)
                    .map(|c| c.ray_gen(size))
                    .map_err(|e| e.to_string())
            }
            CameraModel::Matrix(c) => Ok(c.ray_gen(size)),
            CameraModel::OffAxis(c) => Ok(c.ray_gen(size)),
        }
    }

    /// The committed state, once the camera makes rays. A perspective
    /// camera is checked with a square frame; its aspect is only known for
    /// certain when a frame renders it.
    fn committed(self) -> Result<Option<State>, String> {
        self.ray_gen(UVec2::ONE)?;
        Ok(Some(State::Camera(Derived::Ready(self))))
    }
}
