//! The depth range re-projection must cover: the part of the scene that
//! either eye can see. Layers grow with the range's near end, so in a
//! CAVE, where the volume often reaches past the walls' frustums towards
//! the head, the box is clipped to the frustums before it is measured.

use glam::{DVec3, DVec4};

use crate::geometry::MatrixCamera;
use crate::scene::Scene;

/// What the scene occupies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bounds {
    /// The planner's classic bound (Buchacher & Erdt's), taken
    /// whole.
    Sphere { centre: DVec3, radius: f64 },
    /// The volume's box, clipped to the views.
    Box { lo: DVec3, hi: DVec3 },
}

impl Bounds {
    /// The box around the scene's volumes.
    pub fn of(scene: &Scene) -> Self {
        let (lo, hi) = scene.bounds();
        Bounds::Box {
            lo: lo.as_dvec3(),
            hi: hi.as_dvec3(),
        }
    }

    /// Nearest and farthest depth along `axis` from `eye` of what the
    /// views can see; None if they see none of it.
    pub(super) fn depths(
        &self,
        views: &[&MatrixCamera],
        eye: DVec3,
        axis: DVec3,
    ) -> Option<(f64, f64)> {
        let depth = |p: DVec3| (p - eye).dot(axis);
        let range = |points: &mut dyn Iterator<Item = DVec3>| {
            points.fold(None, |r: Option<(f64, f64)>, p| {
                let z = depth(p);
                Some(r.map_or((z, z), |(a, b)| (a.min(z), b.max(z))))
            })
        };
        match *self {
            Bounds::Sphere { centre, radius } => {
                let z = depth(centre);
                Some((z - radius, z + radius))
            }
            Bounds::Box { lo, hi } => {
                range(&mut views.iter().flat_map(|view| visible_corners(lo, hi, view)))
            }
        }
    }
}

/// The vertices of the box clipped to a view's frustum. A vertex of the
/// clipped solid lies on a box face (and survives clipping that face's
/// polygon) or is a frustum corner inside the box.
fn visible_corners(lo: DVec3, hi: DVec3, view: &MatrixCamera) -> Vec<DVec3> {
    let m = view.proj() * view.view();
    let planes: Vec<DVec4> = (0..3)
        .flat_map(|i| [m.row(3) + m.row(i), m.row(3) - m.row(i)])
        .collect();
    let corner = |i: usize| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    // Each face as four corner indices in order around it.
    const FACES: [[usize; 4]; 6] = [
        [0, 2, 6, 4],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 5, 7, 6],
    ];
    let mut out: Vec<DVec3> = FACES
        .iter()
        .flat_map(|face| {
            planes
                .iter()
                .fold(face.map(corner).to_vec(), |poly, plane| clip(&poly, *plane))
        })
        .collect();
    let slack = 1e-9 * (hi - lo).length();
    for i in 0..8 {
        let ndc = DVec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { -1.0 } else { 1.0 },
        );
        let p = view.unproject(ndc);
        if p.cmpge(lo - slack).all() && p.cmple(hi + slack).all() {
            out.push(p);
        }
    }
    out
}

/// Sutherland-Hodgman: the part of a convex polygon where `plane . (p, 1) >= 0`.
fn clip(poly: &[DVec3], plane: DVec4) -> Vec<DVec3> {
    let side = |p: DVec3| plane.dot(p.extend(1.0));
    let mut out = Vec::with_capacity(poly.len() + 1);
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        let (sa, sb) = (side(a), side(b));
        if sa >= 0.0 {
            out.push(a);
        }
        if (sa >= 0.0) != (sb >= 0.0) {
            out.push(a + (b - a) * (sa / (sa - sb)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::frustum;
    use glam::DMat4;

    /// A camera at the origin looking down -z, 90 degrees, near 1, far 100.
    fn camera() -> MatrixCamera {
        MatrixCamera::new(DMat4::IDENTITY, frustum(-1.0, 1.0, -1.0, 1.0, 1.0, 100.0)).unwrap()
    }

    #[test]
    fn a_box_around_the_eye_is_measured_where_the_frustum_sees_it() {
        let cam = camera();
        // From 5 behind the eye to 10 in front, 2 wide: the frustum
        // (x, y within depth) meets it from the near plane, and its
        // widest visible depth is the far face.
        let b = Bounds::Box {
            lo: DVec3::new(-1.0, -1.0, -10.0),
            hi: DVec3::new(1.0, 1.0, 5.0),
        };
        let (near, far) = b.depths(&[&cam], DVec3::ZERO, DVec3::NEG_Z).unwrap();
        assert!((near - 1.0).abs() < 1e-9, "{near}");
        assert!((far - 10.0).abs() < 1e-9, "{far}");
        // Offset to the side, the box is only seen from depth 3 on: the
        // frustum's edge x = -z reaches x = 3 at depth 3.
        let side = Bounds::Box {
            lo: DVec3::new(3.0, -1.0, -10.0),
            hi: DVec3::new(5.0, 1.0, 5.0),
        };
        let (near, far) = side.depths(&[&cam], DVec3::ZERO, DVec3::NEG_Z).unwrap();
        assert!((near - 3.0).abs() < 1e-9, "{near}");
        assert!((far - 10.0).abs() < 1e-9, "{far}");
    }

    #[test]
    fn a_box_behind_the_eye_is_not_seen() {
        let b = Bounds::Box {
            lo: DVec3::new(-1.0, -1.0, 2.0),
            hi: DVec3::new(1.0, 1.0, 4.0),
        };
        assert_eq!(b.depths(&[&camera()], DVec3::ZERO, DVec3::NEG_Z), None);
    }
}
