use glam::{DVec2, DVec3, UVec2, Vec3};

/// A ray in world space. `direction` is not necessarily unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    pub direction: DVec3,
}

impl Ray {
    pub fn normalized(self) -> Self {
        Self {
            origin: self.origin,
            direction: self.direction.normalize(),
        }
    }

    /// Distance from `p` to the infinite line carrying the ray.
    pub fn distance_to_point(&self, p: DVec3) -> f64 {
        let d = self.direction.normalize();
        let v = p - self.origin;
        (v - v.dot(d) * d).length()
    }

    /// Where the ray's line meets a plane, or `None` if parallel to it.
    pub fn hit_plane(&self, point: DVec3, normal: DVec3) -> Option<DVec3> {
        let denom = self.direction.dot(normal);
        if denom.abs() <= f64::EPSILON * self.direction.length() * normal.length() {
            return None;
        }
        let t = (point - self.origin).dot(normal) / denom;
        Some(self.origin + t * self.direction)
    }
}

/// Normalised image coordinates of pixel (x, y)'s centre in an image of
/// `size`; (0, 0) is the lower-left corner of the image, (1, 1) the upper-right.
pub fn pixel_centre(x: u32, y: u32, size: UVec2) -> DVec2 {
    DVec2::new(
        (f64::from(x) + 0.5) / f64::from(size.x),
        (f64::from(y) + 0.5) / f64::from(size.y),
    )
}

/// Anything that turns image positions into primary rays.
pub trait PrimaryRays {
    /// The ray through normalised image position `s` (see [`pixel_centre`]).
    /// Origin and unnormalised direction are affine in `s`; that is what
    /// lets every camera lower to a [`RayGen`].
    fn ray_through(&self, s: DVec2) -> Ray;

    /// The unit-direction primary ray of pixel (x, y).
    fn pixel_ray(&self, x: u32, y: u32, size: UVec2) -> Ray {
        self.ray_through(pixel_centre(x, y, size)).normalized()
    }

    /// This camera as a per-pixel linear ray generator for an image of `size`.
    fn ray_gen(&self, size: UVec2) -> RayGen {
        let at = |x: f64, y: f64| {
            self.ray_through(DVec2::new(
                (x + 0.5) / f64::from(size.x),
                (y + 0.5) / f64::from(size.y),
            ))
        };
        let (r0, rx, ry) = (at(0.0, 0.0), at(1.0, 0.0), at(0.0, 1.0));
        RayGen {
            origin: r0.origin.as_vec3(),
            origin_dx: (rx.origin - r0.origin).as_vec3(),
            origin_dy: (ry.origin - r0.origin).as_vec3(),
            direction: r0.direction.as_vec3(),
            direction_dx: (rx.direction - r0.direction).as_vec3(),
            direction_dy: (ry.direction - r0.direction).as_vec3(),
            t_near: 0.0,
            t_far: f32::INFINITY,
            eye: self.eye().map(|e| e.as_vec3()),
        }
    }

    /// Where every ray starts from, when the rays leave their origins
    /// elsewhere (the matrix camera's start on the near plane): depth is
    /// measured from here. `None`: from each ray's origin.
    fn eye(&self) -> Option<DVec3> {
        None
    }
}

/// The small single-precision value every camera lowers to: the ray of pixel
/// (0, 0) and how origin and direction change per pixel step. The CPU
/// reference renderer and the GPU shaders both generate rays from it alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayGen {
    pub origin: Vec3,
    pub origin_dx: Vec3,
    pub origin_dy: Vec3,
    pub direction: Vec3,
    pub direction_dx: Vec3,
    pub direction_dy: Vec3,
    /// The part of each ray that sees anything, as distances along the unit
    /// ray from its origin (a camera's near and far clip).
    pub t_near: f32,
    pub t_far: f32,
    /// The point depth is measured from, if not each ray's origin.
    pub eye: Option<Vec3>,
}

impl Default for RayGen {
    fn default() -> Self {
        Self {
            origin: Vec3::ZERO,
            origin_dx: Vec3::ZERO,
            origin_dy: Vec3::ZERO,
            direction: Vec3::ZERO,
            direction_dx: Vec3::ZERO,
            direction_dy: Vec3::ZERO,
            t_near: 0.0,
            t_far: f32::INFINITY,
            eye: None,
        }
    }
}

impl RayGen {
    /// The same rays seeing only from `near` to `far` along each.
    pub fn clipped(mut self, near: f32, far: f32) -> Self {
        self.t_near = near;
        self.t_far = far;
        self
    }

    /// Whether every number is finite (`t_far` may be +inf): a camera
    /// beyond f32's range (an eye at 1e300 in a double-precision host)
    /// gives rays that are not.
    pub fn is_finite(&self) -> bool {
        [
            self.origin,
            self.origin_dx,
            self.origin_dy,
            self.direction,
            self.direction_dx,
            self.direction_dy,
            self.eye.unwrap_or_default(),
        ]
        .iter()
        .all(|v| v.is_finite())
            && self.t_near.is_finite()
            && !self.t_far.is_nan()
    }

    /// How wide a pixel is where its ray starts, at the image's centre
    /// (world units; 0 for a pinhole, whose rays share one origin).
    pub fn pixel_width(&self) -> f32 {
        self.origin_dx.length().max(self.origin_dy.length())
    }

    /// How much wider a pixel grows per unit distance along its (unit)
    /// ray, at the image's centre: the angle it subtends.
    pub fn pixel_spread(&self, size: glam::UVec2) -> f32 {
        let c = size.as_vec2() * 0.5;
        let d = self.direction + c.x * self.direction_dx + c.y * self.direction_dy;
        let len = d.length();
        if len > 0.0 {
            self.direction_dx.length().max(self.direction_dy.length()) / len
        } else {
            0.0
        }
    }

    /// The depth of a point `p`, `t` along its unit ray: from the eye
    /// where the camera has one, else along the ray.
    pub fn depth_at(&self, p: Vec3, t: f32) -> f32 {
        match self.eye {
            Some(eye) => (p - eye).length(),
            None => t,
        }
    }

    /// The point of pixel (x, y)'s ray at `depth` (as [`RayGen::depth_at`]
    /// measures it).
    pub fn point_at_depth(&self, x: u32, y: u32, depth: f32) -> Vec3 {
        let (o, d) = self.pixel_ray(x, y);
        match self.eye {
            Some(eye) => eye + d * depth,
            None => o + d * depth,
        }
    }

    /// The same rays moved by `by` pixels: whole pixels, for the part of
    /// the image whose lower-left pixel is `by` (a cell of a frame
    /// rendered on its own); a fraction, for rays through that point off
    /// each pixel's centre (one sample of each pixel's area).
    pub fn shifted(mut self, by: glam::Vec2) -> Self {
        let (x, y) = (by.x, by.y);
        self.origin += x * self.origin_dx + y * self.origin_dy;
        self.direction += x * self.direction_dx + y * self.direction_dy;
        self
    }

    /// Origin and unit direction of pixel (x, y), in single precision.
    pub fn pixel_ray(&self, x: u32, y: u32) -> (Vec3, Vec3) {
        let (fx, fy) = (x as f32, y as f32);
        let origin = self.origin + fx * self.origin_dx + fy * self.origin_dy;
        let direction = self.direction + fx * self.direction_dx + fy * self.direction_dy;
        (origin, direction.normalize())
    }
}
