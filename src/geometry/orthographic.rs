//! ANARI's orthographic camera: parallel rays from an image rectangle
//! `height` tall, `aspect` times as wide, centred on `position` and facing
//! `direction`; `imageRegion` crops it as for the pinhole.

use glam::{DVec2, DVec3};

use super::error::check_finite;
use super::pinhole::{placed_basis, ImageRegion};
use super::ray::{PrimaryRays, Ray};
use super::{GeometryError, Result, Rounded};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrthographicCamera {
    position: DVec3,
    forward: DVec3,
    image_region: ImageRegion,
    half_right: DVec3,
    half_up: DVec3,
}

impl OrthographicCamera {
    /// `direction` and `up` need not be unit length or orthogonal, only
    /// not parallel; `height` and `aspect` must be positive.
    pub fn new(
        position: DVec3,
        direction: DVec3,
        up: DVec3,
        height: f64,
        aspect: f64,
        image_region: ImageRegion,
    ) -> Result<Self> {
        check_finite("height or aspect", &[height, aspect])?;
        if height <= 0.0 || aspect <= 0.0 {
            return Err(GeometryError::InvalidPinhole {
                reason: format!(
                    "orthographic height and aspect must be positive, got {} and {}",
                    Rounded(height),
                    Rounded(aspect)
                ),
            });
        }
        let (forward, right) = placed_basis(position, direction, up, image_region)?;
        Ok(Self {
            position,
            forward,
            image_region,
            half_right: right * 0.5 * height * aspect,
            half_up: right.cross(forward) * 0.5 * height,
        })
    }
}

impl PrimaryRays for OrthographicCamera {
    fn ray_through(&self, s: DVec2) -> Ray {
        let ndc = 2.0 * self.image_region.map(s) - DVec2::ONE;
        Ray {
            origin: self.position + ndc.x * self.half_right + ndc.y * self.half_up,
            direction: self.forward,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parallel_rays_over_the_image_rectangle() {
        let c = OrthographicCamera::new(
            DVec3::new(1.0, 2.0, 5.0),
            DVec3::new(0.0, 0.0, -2.0),
            DVec3::Y,
            2.0,
            1.5,
            ImageRegion::FULL,
        )
        .unwrap();
        let corner = c.ray_through(DVec2::ZERO);
        let other = c.ray_through(DVec2::ONE);
        assert_eq!(corner.direction, DVec3::NEG_Z);
        assert_eq!(other.direction, DVec3::NEG_Z);
        assert!((corner.origin - DVec3::new(1.0 - 1.5, 1.0, 5.0)).length() < 1e-12);
        assert!((other.origin - DVec3::new(1.0 + 1.5, 3.0, 5.0)).length() < 1e-12);
        assert!(OrthographicCamera::new(
            DVec3::ZERO,
            DVec3::Z,
            DVec3::Z,
            1.0,
            1.0,
            ImageRegion::FULL
        )
        .is_err());
        assert!(OrthographicCamera::new(
            DVec3::ZERO,
            DVec3::Z,
            DVec3::Y,
            0.0,
            1.0,
            ImageRegion::FULL
        )
        .is_err());
    }
}
