use glam::{DVec2, DVec3};

use super::error::check_finite;
use super::{GeometryError, Result};

/// Largest |cos| between the wall's edges, and largest UL misfit relative to
/// the wall's size, still accepted as a rectangle. Hand-written rig files
/// state exact corners; anything further off is a typo worth reporting.
const RECTANGLE_TOLERANCE: f64 = 1e-6;

/// A planar rectangular wall given by three corners: lower-left, lower-right
/// and upper-right, as seen by a viewer in front of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Screen {
    ll: DVec3,
    lr: DVec3,
    ur: DVec3,
}

/// Where an eye's foot point lies on a wall: distances to the four edges in
/// the wall's own axes, and the eye's distance `d` in front of the wall.
/// `left` or `bottom` is negative when the eye is outside the wall's extent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallExtents {
    pub left: f64,
    pub right: f64,
    pub bottom: f64,
    pub top: f64,
    pub distance: f64,
}

impl Screen {
    pub fn new(ll: DVec3, lr: DVec3, ur: DVec3) -> Result<Self> {
        check_finite(
            "wall corner",
            &[ll.x, ll.y, ll.z, lr.x, lr.y, lr.z, ur.x, ur.y, ur.z],
        )?;
        let (width, height) = ((lr - ll).length(), (ur - lr).length());
        let size = width.max(height);
        if width <= f64::EPSILON * size.max(1.0) || height <= f64::EPSILON * size.max(1.0) {
            return Err(GeometryError::ZeroAreaWall { width, height });
        }
        let cos = (lr - ll).dot(ur - lr) / (width * height);
        if cos.abs() > RECTANGLE_TOLERANCE {
            return Err(GeometryError::NotRectangular {
                angle_deg: cos.clamp(-1.0, 1.0).acos().to_degrees(),
            });
        }
        Ok(Self { ll, lr, ur })
    }

    /// A wall whose fourth corner is known too, checked for planarity.
    pub fn with_upper_left(ll: DVec3, lr: DVec3, ur: DVec3, ul: DVec3) -> Result<Self> {
        check_finite("wall corner", &[ul.x, ul.y, ul.z])?;
        let screen = Self::new(ll, lr, ur)?;
        let distance = (ul - screen.ul()).length();
        if distance > RECTANGLE_TOLERANCE * screen.width().max(screen.height()) {
            return Err(GeometryError::NotPlanar { distance });
        }
        Ok(screen)
    }

    pub fn ll(&self) -> DVec3 {
        self.ll
    }
    pub fn lr(&self) -> DVec3 {
        self.lr
    }
    pub fn ur(&self) -> DVec3 {
        self.ur
    }
    pub fn ul(&self) -> DVec3 {
        self.ll + (self.ur - self.lr)
    }
    /// LL, LR, UR, UL: counter-clockwise as seen by the viewer.
    pub fn corners(&self) -> [DVec3; 4] {
        [self.ll, self.lr, self.ur, self.ul()]
    }
    pub fn width(&self) -> f64 {
        (self.lr - self.ll).length()
    }
    pub fn height(&self) -> f64 {
        (self.ur - self.lr).length()
    }
    pub fn centre(&self) -> DVec3 {
        0.5 * (self.ll + self.ur)
    }
    /// Unit vector along the bottom edge, LL to LR.
    pub fn x_axis(&self) -> DVec3 {
        (self.lr - self.ll).normalize()
    }
    /// Unit vector up the right edge, LR to UR.
    pub fn y_axis(&self) -> DVec3 {
        (self.ur - self.lr).normalize()
    }
    /// Unit normal pointing towards the viewer.
    pub fn normal(&self) -> DVec3 {
        self.x_axis().cross(self.y_axis())
    }

    /// The point at normalised wall coordinates `s` (LL = (0,0), UR = (1,1)).
    pub fn point(&self, s: DVec2) -> DVec3 {
        self.ll + s.x * (self.lr - self.ll) + s.y * (self.ur - self.lr)
    }

    /// The eye's position relative to the wall; an eye on or behind the
    /// wall plane has no frustum and is an error.
    pub fn extents(&self, eye: DVec3) -> Result<WallExtents> {
        check_finite("eye position", &[eye.x, eye.y, eye.z])?;
        let rel = eye - self.ll;
        let distance = rel.dot(self.normal());
        // Relative threshold: a distance at rounding-noise level is "on the wall".
        if distance <= 1e-12 * self.width().max(self.height()) {
            return Err(GeometryError::EyeBehindWall { d: distance });
        }
        let left = rel.dot(self.x_axis());
        let bottom = rel.dot(self.y_axis());
        Ok(WallExtents {
            left,
            right: self.width() - left,
            bottom,
            top: self.height() - bottom,
            distance,
        })
    }
}
