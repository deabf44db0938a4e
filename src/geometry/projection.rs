use glam::{DMat4, DVec3, DVec4};

use super::error::check_finite;
use super::{GeometryError, Result, Screen, WallExtents};

/// OpenGL view and projection matrices of one eye looking at one wall
/// (Kooima's generalized perspective projection).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OffAxisProjection {
    pub view: DMat4,
    pub proj: DMat4,
}

impl OffAxisProjection {
    pub fn new(screen: &Screen, eye: DVec3, near: f64, far: f64) -> Result<Self> {
        check_finite("clip plane distance", &[near, far])?;
        if !(near > 0.0 && far > near) {
            return Err(GeometryError::NearFar { near, far });
        }
        let WallExtents {
            left,
            right,
            bottom,
            top,
            distance,
        } = screen.extents(eye)?;
        let scale = near / distance;
        Ok(Self {
            view: view_matrix(screen, eye),
            proj: frustum(
                -left * scale,
                right * scale,
                -bottom * scale,
                top * scale,
                near,
                far,
            ),
        })
    }

    pub fn view_proj(&self) -> DMat4 {
        self.proj * self.view
    }
}

/// World to eye space for a wall: the rotation has the wall axes X, Y, Z as
/// its *rows*, and the translation is `-R * eye`. Building it from columns
/// with `-eye` is a common mistake that only works for walls aligned with
/// the world axes.
fn view_matrix(screen: &Screen, eye: DVec3) -> DMat4 {
    let (x, y, z) = (screen.x_axis(), screen.y_axis(), screen.normal());
    DMat4::from_cols(
        DVec4::new(x.x, y.x, z.x, 0.0),
        DVec4::new(x.y, y.y, z.y, 0.0),
        DVec4::new(x.z, y.z, z.z, 0.0),
        DVec4::new(-x.dot(eye), -y.dot(eye), -z.dot(eye), 1.0),
    )
}

/// The matrix of OpenGL's `glFrustum`.
pub fn frustum(left: f64, right: f64, bottom: f64, top: f64, near: f64, far: f64) -> DMat4 {
    let (w, h, depth) = (right - left, top - bottom, far - near);
    DMat4::from_cols(
        DVec4::new(2.0 * near / w, 0.0, 0.0, 0.0),
        DVec4::new(0.0, 2.0 * near / h, 0.0, 0.0),
        DVec4::new(
            (right + left) / w,
            (top + bottom) / h,
            -(far + near) / depth,
            -1.0,
        ),
        DVec4::new(0.0, 0.0, -2.0 * far * near / depth, 0.0),
    )
}
