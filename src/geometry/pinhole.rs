use glam::{DVec2, DVec3};

use super::error::check_finite;
use super::{GeometryError, PrimaryRays, Ray, Result, Rounded, Screen};

/// The part of a camera's image that is actually rendered, in [0, 1]^2
/// image coordinates (ANARI's `imageRegion`, a FLOAT32_BOX2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageRegion {
    pub min: DVec2,
    pub max: DVec2,
}

impl ImageRegion {
    pub const FULL: Self = Self {
        min: DVec2::ZERO,
        max: DVec2::ONE,
    };

    /// `[min.x, min.y, max.x, max.y]`, the order of ANARI's BOX2.
    pub fn to_array(self) -> [f64; 4] {
        [self.min.x, self.min.y, self.max.x, self.max.y]
    }

    pub(super) fn map(&self, s: DVec2) -> DVec2 {
        self.min + (self.max - self.min) * s
    }
}

impl Default for ImageRegion {
    fn default() -> Self {
        Self::FULL
    }
}

/// Strategy 2: ANARI's perspective camera. Off-axis views are a symmetric
/// frustum widened to contain the wall, cropped back by the image region.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PinholeCamera {
    position: DVec3,
    direction: DVec3,
    up: DVec3,
    fovy: f64,
    aspect: f64,
    image_region: ImageRegion,
    // Derived once: orthonormal basis scaled to the image plane at distance 1.
    forward: DVec3,
    half_right: DVec3,
    half_up: DVec3,
}

/// What ANARI's placed cameras (pinhole and orthographic) check and derive
/// alike: finite inputs, a non-empty image region, and the unit forward
/// and right vectors of `direction` and `up`.
pub(super) fn placed_basis(
    position: DVec3,
    direction: DVec3,
    up: DVec3,
    image_region: ImageRegion,
) -> Result<(DVec3, DVec3)> {
    check_finite("camera position", &position.to_array())?;
    check_finite("camera direction", &direction.to_array())?;
    check_finite("camera up vector", &up.to_array())?;
    check_finite("image region", &image_region.to_array())?;
    let invalid = |reason: String| Err(GeometryError::InvalidPinhole { reason });
    if image_region.max.x == image_region.min.x || image_region.max.y == image_region.min.y {
        return invalid(format!(
            "image region {:?} is empty",
            image_region.to_array()
        ));
    }
    let forward = direction.try_normalize();
    let right = forward.and_then(|f| f.cross(up).try_normalize());
    match (forward, right) {
        (Some(forward), Some(right)) => Ok((forward, right)),
        _ => invalid("direction is zero or parallel to up".into()),
    }
}

impl PinholeCamera {
    /// `fovy` in radians; `direction` and `up` need not be unit length or
    /// orthogonal, only not parallel.
    pub fn new(
        position: DVec3,
        direction: DVec3,
        up: DVec3,
        fovy: f64,
        aspect: f64,
        image_region: ImageRegion,
    ) -> Result<Self> {
        check_finite("fovy, aspect or image region", &[fovy, aspect])?;
        let invalid = |reason: String| Err(GeometryError::InvalidPinhole { reason });
        if !(fovy > 0.0 && fovy < std::f64::consts::PI) {
            return invalid(format!(
                "fovy must be in (0, pi) radians, got {}",
                Rounded(fovy)
            ));
        }
        if aspect <= 0.0 {
            return invalid(format!("aspect must be positive, got {}", Rounded(aspect)));
        }
        let (forward, right) = placed_basis(position, direction, up, image_region)?;
        let tan_half = (0.5 * fovy).tan();
        Ok(Self {
            position,
            direction,
            up,
            fovy,
            aspect,
            image_region,
            forward,
            half_right: right * tan_half * aspect,
            half_up: right.cross(forward) * tan_half,
        })
    }

    /// The pinhole at `eye` whose widened symmetric frustum contains the
    /// whole wall, and the region of its image that is the wall.
    pub fn from_screen(screen: &Screen, eye: DVec3) -> Result<Self> {
        let e = screen.extents(eye)?;
        let half_width = e.left.max(e.right);
        let half_height = e.bottom.max(e.top);
        let image_region = ImageRegion {
            min: DVec2::new(
                (half_width - e.left) / (2.0 * half_width),
                (half_height - e.bottom) / (2.0 * half_height),
            ),
            max: DVec2::new(
                (half_width + e.right) / (2.0 * half_width),
                (half_height + e.top) / (2.0 * half_height),
            ),
        };
        Self::new(
            eye,
            -screen.normal(),
            screen.y_axis(),
            2.0 * (half_height / e.distance).atan(),
            half_width / half_height,
            image_region,
        )
    }

    pub fn position(&self) -> DVec3 {
        self.position
    }
    pub fn direction(&self) -> DVec3 {
        self.direction
    }
    pub fn up(&self) -> DVec3 {
        self.up
    }
    /// Vertical field of view in radians.
    pub fn fovy(&self) -> f64 {
        self.fovy
    }
    pub fn aspect(&self) -> f64 {
        self.aspect
    }
    pub fn image_region(&self) -> ImageRegion {
        self.image_region
    }
}

impl PrimaryRays for PinholeCamera {
    fn ray_through(&self, s: DVec2) -> Ray {
        let ndc = 2.0 * self.image_region.map(s) - DVec2::ONE;
        Ray {
            origin: self.position,
            direction: self.forward + ndc.x * self.half_right + ndc.y * self.half_up,
        }
    }
}
