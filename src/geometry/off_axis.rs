use glam::{DVec2, DVec3};

use super::{OffAxisProjection, PrimaryRays, Ray, Result, Screen};

/// caveray's native off-axis camera: rays from the eye through the wall,
/// with no matrices or pinhole in between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OffAxisCamera {
    screen: Screen,
    eye: DVec3,
}

impl OffAxisCamera {
    pub fn new(screen: Screen, eye: DVec3) -> Result<Self> {
        screen.extents(eye)?;
        Ok(Self { screen, eye })
    }

    pub fn screen(&self) -> &Screen {
        &self.screen
    }
    pub fn eye(&self) -> DVec3 {
        self.eye
    }

    /// The OpenGL matrices of this view, for strategy 1 and for hosts.
    pub fn projection(&self, near: f64, far: f64) -> Result<OffAxisProjection> {
        OffAxisProjection::new(&self.screen, self.eye, near, far)
    }
}

impl PrimaryRays for OffAxisCamera {
    fn ray_through(&self, s: DVec2) -> Ray {
        Ray {
            origin: self.eye,
            direction: self.screen.point(s) - self.eye,
        }
    }
}
