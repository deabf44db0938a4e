//! A camera run backwards: the image position and ray distance at which a
//! view sees a world point. Warps project into the source view (gathers)
//! and into the target view (the grid's mesh).

use glam::{Mat3, Vec2, Vec3};

use crate::geometry::RayGen;

/// How a view's rays relate to world points: all through one centre (a
/// pinhole, an off-axis wall, a matrix camera through its eye), or all
/// parallel (orthographic).
#[derive(Clone, Copy, Debug)]
pub struct Projector {
    rays: RayGen,
    kind: Kind,
}

/// A point as a view sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seen {
    /// Image position, pixels.
    pub at: Vec2,
    /// Distance along the ray there, from its origin.
    pub along: f32,
    /// That ray's unit direction.
    pub direction: Vec3,
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    /// Columns direction, direction_dx, direction_dy, inverted.
    Central { centre: Vec3, inverse: Mat3 },
    /// Columns origin_dx, origin_dy, direction, inverted.
    Parallel { inverse: Mat3 },
}

impl Projector {
    /// The projector of `rays`, or why there is none (rays that neither
    /// share a centre nor run parallel, or a degenerate image).
    pub fn new(rays: &RayGen) -> Result<Self, String> {
        let tiny = |v: Vec3, scale: f32| v.length() <= 1e-6 * scale.max(f32::MIN_POSITIVE);
        let spread = rays.direction.length();
        let kind = if let Some(eye) = rays.eye {
            central(rays, eye)
        } else if tiny(rays.origin_dx, spread) && tiny(rays.origin_dy, spread) {
            central(rays, rays.origin)
        } else if tiny(rays.direction_dx, spread) && tiny(rays.direction_dy, spread) {
            let m = Mat3::from_cols(rays.origin_dx, rays.origin_dy, rays.direction);
            (m.determinant().abs() > 0.0).then(|| Kind::Parallel {
                inverse: m.inverse(),
            })
        } else {
            return Err("the view's rays neither meet in one eye nor run parallel".into());
        };
        let kind = kind.ok_or("the view's image is degenerate (its pixel steps are parallel)")?;
        Ok(Self { rays: *rays, kind })
    }

    /// The inverse matrix's columns and the centre, w = 0 for rays
    /// through the centre and 1 for parallel ones (what the GPU warp reads).
    pub fn packed(&self) -> [[f32; 4]; 4] {
        let (inverse, centre, kind) = match self.kind {
            Kind::Central { centre, inverse } => (inverse, centre, 0.0),
            Kind::Parallel { inverse } => (inverse, self.rays.origin, 1.0),
        };
        [
            inverse.x_axis.extend(0.0).to_array(),
            inverse.y_axis.extend(0.0).to_array(),
            inverse.z_axis.extend(0.0).to_array(),
            centre.extend(kind).to_array(),
        ]
    }

    pub fn rays(&self) -> &RayGen {
        &self.rays
    }

    /// Where `p` appears in the image, in pixels (pixel (x, y) spans
    /// [x, x + 1) x [y, y + 1)), and how far along that position's unit
    /// ray from its origin; `None` for a point behind the eye.
    pub fn locate(&self, p: Vec3) -> Option<Seen> {
        let r = &self.rays;
        let (px, py) = match self.kind {
            Kind::Central { centre, inverse } => {
                let v = inverse * (p - centre);
                if v.x <= 0.0 {
                    return None;
                }
                (v.y / v.x, v.z / v.x)
            }
            Kind::Parallel { inverse } => {
                let v = inverse * (p - r.origin);
                (v.x, v.y)
            }
        };
        let origin = r.origin + px * r.origin_dx + py * r.origin_dy;
        let dir = (r.direction + px * r.direction_dx + py * r.direction_dy).normalize();
        let at = Vec2::new(px + 0.5, py + 0.5);
        at.is_finite().then_some(Seen {
            at,
            along: (p - origin).dot(dir),
            direction: dir,
        })
    }

    /// The unit normal of the image plane: the plane the pixel steps span
    /// (a wall for an off-axis view), facing along the view.
    pub fn image_normal(&self) -> Vec3 {
        let r = &self.rays;
        let n = match self.kind {
            Kind::Central { .. } => r.direction_dx.cross(r.direction_dy),
            Kind::Parallel { .. } => r.origin_dx.cross(r.origin_dy),
        };
        let n = n.normalize_or_zero();
        if n.dot(r.direction) < 0.0 {
            -n
        } else {
            n
        }
    }
}

fn central(rays: &RayGen, centre: Vec3) -> Option<Kind> {
    let m = Mat3::from_cols(rays.direction, rays.direction_dx, rays.direction_dy);
    (m.determinant().abs() > 0.0).then(|| Kind::Central {
        centre,
        inverse: m.inverse(),
    })
}
