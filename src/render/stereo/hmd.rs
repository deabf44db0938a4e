//! Buchacher & Erdt's HMD views as OpenGL matrices: two parallel, symmetric
//! frustums whose eyes sit e apart, orbiting a bounding sphere centred at
//! the origin whose near side touches the image plane.

use glam::{DMat4, DVec3};

use super::plan::HmdStereo;
use crate::geometry::{frustum, GeometryError, MatrixCamera};

impl HmdStereo {
    /// Left and right eye after turning `angle` radians about +y from the
    /// +z axis; the eyes look at the origin. Needs a bounding radius.
    pub fn eyes(&self, angle: f64) -> Result<(MatrixCamera, MatrixCamera), GeometryError> {
        let r = self.radius.ok_or_else(|| GeometryError::NonPerspective {
            reason: "the HMD views need a bounding radius to place the eyes".into(),
        })?;
        let back = DVec3::new(angle.sin(), 0.0, angle.cos());
        let centre = (self.focal + r) * back;
        let right_dir = DVec3::Y.cross(back).normalize();
        let near = 0.1 * self.focal;
        let half = near * (0.5 * self.fov).tan();
        let proj = frustum(-half, half, -half, half, near, self.focal + 2.0 * r + 1.0);
        let up = back.cross(right_dir);
        let eye = |side: f64| {
            let at = centre + side * 0.5 * self.eye_distance * right_dir;
            let pose = DMat4::from_cols(
                right_dir.extend(0.0),
                up.extend(0.0),
                back.extend(0.0),
                at.extend(1.0),
            );
            MatrixCamera::new(pose.inverse(), proj)
        };
        Ok((eye(-1.0)?, eye(1.0)?))
    }
}
