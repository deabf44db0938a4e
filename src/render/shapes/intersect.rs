//! Ray against one primitive, as the BVH's leaves test them.

use glam::{Vec2, Vec3};

/// Where `o + t d` crosses triangle (a, b, c), from either side, with the
/// weights of b and c there (Möller and Trumbore's test).
pub fn triangle(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<(f32, Vec2)> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((e2.dot(q) * inv, Vec2::new(u, v)))
}

/// The first `t` in `(t_min, t_max)` where `o + t d` meets the sphere at
/// `c` of radius `r` (the far side from inside it). `d` need not be of
/// unit length: t is the caller's ray parameter.
pub fn sphere(o: Vec3, d: Vec3, c: Vec3, r: f32, t_min: f32, t_max: f32) -> Option<f32> {
    let a = d.length_squared();
    if a == 0.0 {
        return None;
    }
    let oc = o - c;
    let b = oc.dot(d);
    // The distance from c to the ray's closest point, squared, computed
    // from the perpendicular part: stable far from the sphere.
    let perp = oc - d * (b / a);
    let disc = r * r - perp.length_squared();
    if disc < 0.0 {
        return None;
    }
    let h = (a * disc).sqrt();
    let near = (-b - h) / a;
    let far = (-b + h) / a;
    [near, far].into_iter().find(|&t| t > t_min && t < t_max)
}

/// The first `t` in `(t_min, t_max)` where `o + t d` meets the cylinder
/// of radius `r` from `a` to `b`, with the discs that close it where
/// `caps` says, and how far along the axis (0 at a, 1 at b) it is met.
pub fn cylinder(
    o: Vec3,
    d: Vec3,
    (a, b, r): (Vec3, Vec3, f32),
    caps: [bool; 2],
    (t_min, t_max): (f32, f32),
) -> Option<(f32, f32)> {
    let length = a.distance(b);
    let axis = (b - a) / length;
    let oc = o - a;
    let (along_d, along_o) = (d.dot(axis), oc.dot(axis));
    let (dp, op) = (d - axis * along_d, oc - axis * along_o);
    let mut best: Option<(f32, f32)> = None;
    let mut consider = |t: f32, s: f32| {
        if t > t_min && t < t_max && best.is_none_or(|(bt, _)| t < bt) {
            best = Some((t, s));
        }
    };
    let qa = dp.length_squared();
    if qa > 0.0 {
        let qb = op.dot(dp);
        // From the perpendicular part, as the sphere's: stable far away.
        let closest = op - dp * (qb / qa);
        let disc = r * r - closest.length_squared();
        if disc >= 0.0 {
            let h = (qa * disc).sqrt();
            for t in [(-qb - h) / qa, (-qb + h) / qa] {
                let s = along_o + t * along_d;
                if (0.0..=length).contains(&s) {
                    consider(t, s / length);
                }
            }
        }
    }
    if along_d != 0.0 {
        for (end, closed, s) in [(a, caps[0], 0.0), (b, caps[1], 1.0)] {
            if !closed {
                continue;
            }
            let t = (end - o).dot(axis) / along_d;
            if (o + d * t - end).length_squared() <= r * r {
                consider(t, s);
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_gives_distance_and_weights_from_both_sides() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let (t, w) = triangle(Vec3::new(0.25, 0.5, 2.0), -Vec3::Z, a, b, c).unwrap();
        assert!((t - 2.0).abs() < 1e-6 && (w - Vec2::new(0.25, 0.5)).length() < 1e-6);
        let (t, _) = triangle(Vec3::new(0.25, 0.5, -3.0), Vec3::Z, a, b, c).unwrap();
        assert!((t - 3.0).abs() < 1e-6);
        assert!(triangle(Vec3::new(0.75, 0.75, 2.0), -Vec3::Z, a, b, c).is_none());
        assert!(triangle(Vec3::new(0.25, 0.5, 2.0), Vec3::X, a, b, c).is_none());
    }

    #[test]
    fn cylinder_gives_side_caps_and_axis_position() {
        let (a, b) = (Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0));
        let span = (0.0, 100.0);
        // From the side, at a quarter of the length.
        let (t, s) = cylinder(
            Vec3::new(5.0, 0.0, 0.5),
            -Vec3::X,
            (a, b, 1.0),
            [false; 2],
            span,
        )
        .unwrap();
        assert!((t - 4.0).abs() < 1e-5 && (s - 0.25).abs() < 1e-6);
        // Along the axis: only a cap stops the ray; an open tube lets it through to nothing.
        let down = (Vec3::new(0.2, 0.0, 5.0), -Vec3::Z);
        assert!(cylinder(down.0, down.1, (a, b, 1.0), [false; 2], span).is_none());
        let (t, s) = cylinder(down.0, down.1, (a, b, 1.0), [false, true], span).unwrap();
        assert!((t - 3.0).abs() < 1e-5 && s == 1.0);
        let (t, s) = cylinder(down.0, down.1, (a, b, 1.0), [true, false], span).unwrap();
        assert!((t - 5.0).abs() < 1e-5 && s == 0.0);
        // Past the ends the side is not there.
        assert!(cylinder(
            Vec3::new(5.0, 0.0, 2.5),
            -Vec3::X,
            (a, b, 1.0),
            [true; 2],
            span
        )
        .is_none());
    }

    #[test]
    fn sphere_gives_near_side_then_far_side() {
        let o = Vec3::new(0.0, 0.0, 5.0);
        let t = sphere(o, -Vec3::Z, Vec3::ZERO, 1.0, 0.0, 100.0).unwrap();
        assert!((t - 4.0).abs() < 1e-5);
        // From inside: the far side.
        let t = sphere(Vec3::ZERO, Vec3::X, Vec3::ZERO, 2.0, 0.0, 100.0).unwrap();
        assert!((t - 2.0).abs() < 1e-6);
        // A direction of length 2 halves t.
        let t = sphere(o, -Vec3::Z * 2.0, Vec3::ZERO, 1.0, 0.0, 100.0).unwrap();
        assert!((t - 2.0).abs() < 1e-5);
        assert!(sphere(o, -Vec3::Z, Vec3::new(1.5, 0.0, 0.0), 1.0, 0.0, 100.0).is_none());
        assert!(sphere(o, -Vec3::Z, Vec3::ZERO, 1.0, 0.0, 3.0).is_none());
    }
}
