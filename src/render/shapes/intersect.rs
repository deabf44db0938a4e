//! Ray against one primitive, as the BVH's leaves test them.

use glam::{Vec2, Vec3};

/// A ray direction's frame for the watertight triangle test (Woop,
/// Benthin and Wald, "Watertight Ray/Triangle Intersection", 2013): the
/// axis along which it is longest becomes z, and a shear turns the ray
/// into that axis. Computed once per ray.
#[derive(Clone, Copy, Debug)]
pub struct Shear {
    /// The axes that become x, y and z; x and y swapped where d points
    /// down z, so that a triangle's winding keeps its sign.
    pub k: [usize; 3],
    /// d[kx] / d[kz], d[ky] / d[kz] and 1 / d[kz].
    pub s: [f32; 3],
}

impl Shear {
    pub fn of(d: Vec3) -> Shear {
        let m = d.abs();
        let kz = if m.x >= m.y && m.x >= m.z {
            0
        } else if m.y >= m.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Shear {
            k: [kx, ky, kz],
            s: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]],
        }
    }
}

/// Where `o + t d` crosses triangle (a, b, c), from either side, with the
/// weights of b and c there.
pub fn triangle(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<(f32, Vec2)> {
    sheared_triangle(o, &Shear::of(d), [a, b, c])
}

/// [`triangle`] with the ray's shear given. Each edge's function is
/// computed from its two corners alone, in the ray's frame, so a ray
/// through an edge two triangles share is inside at least one of them
/// (both when it lies exactly on it): no pixel sees through a closed mesh.
/// wide.rs repeats this arithmetic operation for operation, lane by lane.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn sheared_triangle(o: Vec3, shear: &Shear, [a, b, c]: [Vec3; 3]) -> Option<(f32, Vec2)> {
    let [kx, ky, kz] = shear.k;
    let [sx, sy, sz] = shear.s;
    let (a, b, c) = (a - o, b - o, c - o);
    let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
    let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
    let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 || !(det.abs() < f32::INFINITY) {
        return None;
    }
    let t = u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz]);
    let inv = 1.0 / det;
    Some((t * inv, Vec2::new(v * inv, w * inv)))
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

/// An end of a cone or curve segment: its centre and radius.
pub type End = (Vec3, f32);

/// The first `t` in `(t_min, t_max)` where `o + t d` meets the cone from
/// `a` to `b` (of the radii they give there; a cylinder where the two
/// agree), with the discs that close it where `caps` says, and how far
/// along the axis (0 at a, 1 at b) it is met.
pub fn cone(
    o: Vec3,
    d: Vec3,
    (a, b): (End, End),
    caps: [bool; 2],
    (t_min, t_max): (f32, f32),
) -> Option<(f32, f32)> {
    let length = a.0.distance(b.0);
    let axis = (b.0 - a.0) / length;
    let dd = d.length_squared();
    if dd == 0.0 {
        return None;
    }
    // Solved from the ray's point nearest the middle of the axis, so that
    // a far eye loses no precision to the quadratic's cancellation.
    let shift = ((a.0 + b.0) * 0.5 - o).dot(d) / dd;
    let oc = o + d * shift - a.0;
    let slope = (b.1 - a.1) / length;
    let (along_d, along_o) = (d.dot(axis), oc.dot(axis));
    let (dp, op) = (d - axis * along_d, oc - axis * along_o);
    // The radius along the ray: r0 + rd t.
    let (r0, rd) = (a.1 + slope * along_o, slope * along_d);
    let mut best: Option<(f32, f32)> = None;
    let mut consider = |t: f32, s: f32| {
        if t > t_min && t < t_max && best.is_none_or(|(bt, _)| t < bt) {
            best = Some((t, s));
        }
    };
    let qa = dp.length_squared() - rd * rd;
    let qb = op.dot(dp) - r0 * rd;
    let qc = op.length_squared() - r0 * r0;
    let disc = qb * qb - qa * qc;
    if disc >= 0.0 {
        // The stable pair of roots, which stays finite as qa goes to 0
        // (a ray along the cone's slant).
        let q = -(qb + disc.sqrt().copysign(qb));
        for local in [q / qa, qc / q] {
            let s = along_o + local * along_d;
            if local.is_finite() && (0.0..=length).contains(&s) {
                consider(local + shift, s / length);
            }
        }
    }
    if along_d != 0.0 {
        for ((end, r), closed, s) in [(a, caps[0], 0.0), (b, caps[1], 1.0)] {
            if !closed {
                continue;
            }
            let local = (end - a.0 - oc).dot(axis) / along_d;
            if (oc + d * local - (end - a.0)).length_squared() <= r * r {
                consider(local + shift, s);
            }
        }
    }
    best
}

/// The cone that joins the spheres at `a` and `b` tangentially (the
/// side of their hull), as two ends, or none where one sphere holds the
/// other.
pub fn tangent_cone(a: End, b: End) -> Option<(End, End)> {
    let length = a.0.distance(b.0);
    // The hull's normal in a plane through the axis: (along, across).
    let along = (a.1 - b.1) / length;
    if along.is_nan() || along.abs() >= 1.0 {
        return None;
    }
    let across = (1.0 - along * along).sqrt();
    let axis = (b.0 - a.0) / length;
    Some((
        (a.0 + axis * (a.1 * along), a.1 * across),
        (b.0 + axis * (b.1 * along), b.1 * across),
    ))
}

/// The first `t` in `(t_min, t_max)` where `o + t d` meets the round
/// curve segment from `a` to `b` (the hull of the spheres there), and how
/// far along it (0 at a, 1 at b) the point nearest the hit lies.
pub fn curve(o: Vec3, d: Vec3, (a, b): (End, End), span: (f32, f32)) -> Option<(f32, f32)> {
    let mut best: Option<(f32, f32)> = None;
    for (end, s) in [(a, 0.0), (b, 1.0)] {
        if let Some(t) = sphere(o, d, end.0, end.1, span.0, best.map_or(span.1, |b| b.0)) {
            best = Some((t, s));
        }
    }
    if let Some(side) = tangent_cone(a, b) {
        let limit = best.map_or(span.1, |b| b.0);
        if let Some((t, _)) = cone(o, d, side, [false; 2], (span.0, limit)) {
            let axis = b.0 - a.0;
            let s = ((o + d * t - a.0).dot(axis) / axis.length_squared()).clamp(0.0, 1.0);
            best = Some((t, s));
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
        let (a, b) = ((Vec3::ZERO, 1.0), (Vec3::new(0.0, 0.0, 2.0), 1.0));
        let span = (0.0, 100.0);
        // From the side, at a quarter of the length.
        let (t, s) = cone(Vec3::new(5.0, 0.0, 0.5), -Vec3::X, (a, b), [false; 2], span).unwrap();
        assert!((t - 4.0).abs() < 1e-5 && (s - 0.25).abs() < 1e-6);
        // Along the axis: only a cap stops the ray; an open tube lets it through to nothing.
        let down = (Vec3::new(0.2, 0.0, 5.0), -Vec3::Z);
        assert!(cone(down.0, down.1, (a, b), [false; 2], span).is_none());
        let (t, s) = cone(down.0, down.1, (a, b), [false, true], span).unwrap();
        assert!((t - 3.0).abs() < 1e-5 && s == 1.0);
        let (t, s) = cone(down.0, down.1, (a, b), [true, false], span).unwrap();
        assert!((t - 5.0).abs() < 1e-5 && s == 0.0);
        // Past the ends the side is not there.
        assert!(cone(Vec3::new(5.0, 0.0, 2.5), -Vec3::X, (a, b), [true; 2], span).is_none());
        // Far away, as a CAVE's far wall may be, the side stays exact.
        let (t, _) = cone(
            Vec3::new(1e5, 0.0, 1.0),
            -Vec3::X,
            (a, b),
            [false; 2],
            (0.0, 1e6),
        )
        .unwrap();
        assert!((t - (1e5 - 1.0)).abs() < 0.02, "{t}");
    }

    #[test]
    fn cone_side_follows_the_radius_and_its_caps_are_sized_by_their_end() {
        // Radius 1 at z = 0 to 0 at z = 2: at z = 1 the radius is 0.5.
        let (a, b) = ((Vec3::ZERO, 1.0), (Vec3::new(0.0, 0.0, 2.0), 0.0));
        let span = (0.0, 100.0);
        let (t, s) = cone(Vec3::new(5.0, 0.0, 1.0), -Vec3::X, (a, b), [true; 2], span).unwrap();
        assert!((t - 4.5).abs() < 1e-5 && (s - 0.5).abs() < 1e-6, "{t} {s}");
        // Down the axis at 0.8 from it: through the side where the radius is 0.8 (z = 0.4).
        let (t, s) = cone(Vec3::new(0.8, 0.0, 5.0), -Vec3::Z, (a, b), [false; 2], span).unwrap();
        assert!((t - 4.6).abs() < 1e-5 && (s - 0.2).abs() < 1e-5, "{t} {s}");
        // Up from below: the first end's disc, of radius 1.
        let (t, s) = cone(
            Vec3::new(0.8, 0.0, -1.0),
            Vec3::Z,
            (a, b),
            [true, false],
            span,
        )
        .unwrap();
        assert!((t - 1.0).abs() < 1e-5 && s == 0.0);
        assert!(cone(Vec3::new(1.2, 0.0, -1.0), Vec3::Z, (a, b), [true; 2], span).is_none());
        // A ray along the slant (parallel to a generator line) still meets the cone once.
        let slant = Vec3::new(-0.5, 0.0, 1.0);
        let (t, _) = cone(Vec3::new(0.5, 0.0, -1.0), slant, (a, b), [false; 2], span).unwrap();
        let p = Vec3::new(0.5, 0.0, -1.0) + slant * t;
        assert!((p.x.abs() - (1.0 - p.z * 0.5)).abs() < 1e-4, "{p}");
    }

    #[test]
    fn curve_is_the_hull_of_its_end_spheres() {
        let (a, b) = ((Vec3::ZERO, 1.0), (Vec3::new(4.0, 0.0, 0.0), 0.5));
        let span = (0.0, 100.0);
        // Beyond the first end: its sphere.
        let (t, s) = curve(Vec3::new(-0.5, 0.0, 5.0), -Vec3::Z, (a, b), span).unwrap();
        assert!(
            (t - (5.0 - 0.75f32.sqrt())).abs() < 1e-4 && s == 0.0,
            "{t} {s}"
        );
        // Beyond the second end: its sphere.
        let (t, s) = curve(Vec3::new(4.25, 0.0, 5.0), -Vec3::Z, (a, b), span).unwrap();
        assert!(
            (t - (5.0 - 0.1875f32.sqrt())).abs() < 1e-4 && s == 1.0,
            "{t} {s}"
        );
        // In the middle: the tangent cone, whose distance from the axis
        // at x = 2 is its hull radius there.
        let (t, s) = curve(Vec3::new(2.0, 0.0, 5.0), -Vec3::Z, (a, b), span).unwrap();
        let along = (1.0f32 - 0.5) / 4.0;
        let across = (1.0 - along * along).sqrt();
        let (lo, hi) = (
            (1.0 * along, 1.0 * across),
            (4.0 + 0.5 * along, 0.5 * across),
        );
        let expect = lo.1 + (hi.1 - lo.1) * (2.0 - lo.0) / (hi.0 - lo.0);
        assert!(
            (t - (5.0 - expect)).abs() < 1e-4 && (s - 0.5).abs() < 1e-3,
            "{t} {s}"
        );
        // One sphere inside the other: the larger alone.
        let inside = ((Vec3::ZERO, 2.0), (Vec3::X, 0.5));
        assert!(tangent_cone(inside.0, inside.1).is_none());
        let (t, _) = curve(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z, inside, span).unwrap();
        assert!((t - 3.0).abs() < 1e-5);
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
