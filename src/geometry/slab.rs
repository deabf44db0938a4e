//! The slab test: where a ray meets an axis-aligned box, in the single
//! precision both renderers march in.

use glam::Vec3;

/// Where a ray enters and leaves the box, clipped to the camera's
/// `(near, far)` (`near` >= 0).
pub fn enter_exit(
    o: Vec3,
    d: Vec3,
    lo: Vec3,
    hi: Vec3,
    (near, far): (f32, f32),
) -> Option<(f32, f32)> {
    let safe = |x: f32| {
        if x.abs() < 1e-20 {
            1e-20_f32.copysign(x)
        } else {
            x
        }
    };
    let inv = Vec3::new(safe(d.x), safe(d.y), safe(d.z)).recip();
    let ta = (lo - o) * inv;
    let tb = (hi - o) * inv;
    let t0 = ta.min(tb).max_element().max(near);
    let t1 = ta.max(tb).min_element().min(far);
    (t1 > t0).then_some((t0, t1))
}
