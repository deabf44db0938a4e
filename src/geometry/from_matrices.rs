use glam::{DMat4, DVec3};

use super::{GeometryError, MatrixCamera, PinholeCamera, Result, Screen};

/// Strategy 3's answer: a pinhole camera equivalent to a view/projection
/// pair, the eye it implies and the far-plane rectangle it looks through.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecoveredPinhole {
    pub camera: PinholeCamera,
    pub eye: DVec3,
    /// The far plane's corners LL, LR, UR, UL in world space: the wall,
    /// scaled about the eye (a pinhole camera cannot tell the difference).
    pub corners: [DVec3; 4],
}

/// Recovers the pinhole camera behind any OpenGL perspective view and
/// projection: the eye is where the left/right and bottom/top frustum plane
/// pairs meet, taken as the midpoint of the shortest segment between the
/// two intersection lines so that rounding cannot make it miss.
pub fn pinhole_from_matrices(view: DMat4, proj: DMat4) -> Result<RecoveredPinhole> {
    let m = MatrixCamera::new(view, proj)?;
    let corner = |x: f64, y: f64, z: f64| m.unproject(DVec3::new(x, y, z));
    let [nll, nlr, nur, nul] =
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| corner(x, y, -1.0));
    let [fll, flr, fur, ful] =
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| corner(x, y, 1.0));

    let left = Plane::through_quad(nll, fll, ful, nul);
    let right = Plane::through_quad(nlr, flr, fur, nur);
    let bottom = Plane::through_quad(nll, fll, flr, nlr);
    let top = Plane::through_quad(nul, ful, fur, nur);
    let vertical = left.intersect(&right, "left and right")?;
    let horizontal = bottom.intersect(&top, "bottom and top")?;
    let eye = vertical.closest_midpoint(&horizontal)?;

    let screen =
        Screen::with_upper_left(fll, flr, fur, ful).map_err(|e| GeometryError::NonPerspective {
            reason: format!("the far plane is not a rectangle ({e})"),
        })?;
    Ok(RecoveredPinhole {
        camera: PinholeCamera::from_screen(&screen, eye)?,
        eye,
        corners: [fll, flr, fur, ful],
    })
}

/// Plane `normal . x = offset` with a unit normal.
struct Plane {
    normal: DVec3,
    offset: f64,
}

impl Plane {
    /// Plane of a quad a-b-c-d, from its diagonals (robust for thin quads).
    fn through_quad(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Self {
        let normal = (c - a).cross(d - b).normalize();
        let offset = normal.dot(0.25 * (a + b + c + d));
        Self { normal, offset }
    }

    fn intersect(&self, other: &Plane, which: &'static str) -> Result<Line> {
        let direction = self.normal.cross(other.normal);
        let len2 = direction.length_squared();
        if len2.is_nan() || len2 <= 1e-20 {
            return Err(GeometryError::ParallelPlanes { which });
        }
        let point = (self.offset * other.normal.cross(direction)
            + other.offset * direction.cross(self.normal))
            / len2;
        Ok(Line {
            point,
            direction: direction / len2.sqrt(),
        })
    }
}

struct Line {
    point: DVec3,
    direction: DVec3,
}

impl Line {
    fn closest_midpoint(&self, other: &Line) -> Result<DVec3> {
        let w = self.point - other.point;
        let b = self.direction.dot(other.direction);
        let denom = 1.0 - b * b;
        if denom.is_nan() || denom <= 1e-20 {
            return Err(GeometryError::NonPerspective {
                reason: "the frustum's edge planes meet in parallel lines".into(),
            });
        }
        let (d, e) = (self.direction.dot(w), other.direction.dot(w));
        let t = (b * e - d) / denom;
        let s = (e - b * d) / denom;
        Ok(0.5 * ((self.point + t * self.direction) + (other.point + s * other.direction)))
    }
}
