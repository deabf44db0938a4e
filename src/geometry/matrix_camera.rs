use glam::{DMat4, DVec2, DVec3, DVec4, Mat4};

use super::error::check_finite;
use super::{GeometryError, PrimaryRays, Ray, Result};

/// Strategy 1: rays from the inverse of OpenGL view and projection matrices
/// (column-major, NDC z in [-1, 1]), exactly what a CAVE host already has.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatrixCamera {
    view: DMat4,
    proj: DMat4,
    inverse: DMat4,
}

impl MatrixCamera {
    pub fn new(view: DMat4, proj: DMat4) -> Result<Self> {
        check_finite("view matrix", &view.to_cols_array())?;
        check_finite("projection matrix", &proj.to_cols_array())?;
        let view_proj = proj * view;
        let det = view_proj.determinant();
        let inverse = view_proj.inverse();
        // A residual test is independent of the rig's units, unlike |det|.
        let residual = (view_proj * inverse - DMat4::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if det == 0.0 || !det.is_finite() || !inverse.is_finite() || residual > 1e-6 {
            return Err(GeometryError::SingularMatrix { det });
        }
        // The homogeneous w of an unprojected point must not vary across the
        // near and far planes, or rays would not be affine in the pixel.
        let w_row = inverse.row(3);
        let (w_near, w_far) = (w_row.w - w_row.z, w_row.w + w_row.z);
        if w_near * w_far <= 0.0 {
            return Err(GeometryError::NonPerspective {
                reason: "near or far plane maps to infinity or behind the eye".into(),
            });
        }
        // Relative to the larger w: a far plane a billion near planes away
        // (what hosts without a far plane get) leaves rounding noise of
        // the near plane's size in an off-axis frustum's inverse.
        if w_row.x.abs() + w_row.y.abs() > 1e-9 * w_near.abs().max(w_far.abs()) {
            return Err(GeometryError::NonPerspective {
                reason: "depth varies across the image plane (projective skew)".into(),
            });
        }
        Ok(Self {
            view,
            proj,
            inverse,
        })
    }

    /// The single-precision matrices an OpenGL host or the C API hands over.
    pub fn from_f32(view: Mat4, proj: Mat4) -> Result<Self> {
        Self::new(view.as_dmat4(), proj.as_dmat4())
    }

    pub fn view(&self) -> DMat4 {
        self.view
    }
    pub fn proj(&self) -> DMat4 {
        self.proj
    }

    /// World-space point of normalised device coordinates `ndc`.
    pub fn unproject(&self, ndc: DVec3) -> DVec3 {
        let p = self.inverse * DVec4::new(ndc.x, ndc.y, ndc.z, 1.0);
        p.truncate() / p.w
    }

    /// Normalised device coordinates of world point `p`.
    pub fn project(&self, p: DVec3) -> DVec3 {
        let c = self.proj * self.view * p.extend(1.0);
        c.truncate() / c.w
    }
}

impl PrimaryRays for MatrixCamera {
    /// A perspective projection's rays meet at the eye, the view's origin;
    /// an orthographic one's have none.
    fn eye(&self) -> Option<DVec3> {
        (self.proj.w_axis.w.abs() < 1e-12).then(|| self.view.inverse().w_axis.truncate())
    }

    fn ray_through(&self, s: DVec2) -> Ray {
        let ndc = 2.0 * s - DVec2::ONE;
        let near = self.unproject(ndc.extend(-1.0));
        let far = self.unproject(ndc.extend(1.0));
        Ray {
            origin: near,
            direction: far - near,
        }
    }
}
