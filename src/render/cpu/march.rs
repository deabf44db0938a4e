use glam::{Vec3, Vec4};

use super::sample::{correct, Field, Mixture};
use crate::geometry::RayGen;
use crate::render::settings::{Shading, DIRECTIONAL_STEPS, SHADOW_AMBIENT, SHADOW_STEPS};
use crate::scene::MAX_VOLUMES;

/// What one primary ray produced.
pub(super) struct RayResult {
    /// Composited over the background.
    pub color: Vec4,
    pub depth: f32,
    /// Volume samples taken, primary and shading.
    pub samples: u32,
}

/// Marches one primary ray of `rays` with unit direction `dir` through
/// every volume at once: one step sequence over the union of their spans,
/// each sample mixing the volumes whose span holds it.
pub(super) fn march(field: &Field, rays: &RayGen, origin: Vec3, dir: Vec3, bg: Vec4) -> RayResult {
    let mut samples = 0;
    let plan = field.plan;
    let mut acc = Vec4::ZERO;
    let mut depth = f32::INFINITY;
    let clip = (rays.t_near, rays.t_far);
    // Each volume's span along the ray, found in its grid, where the
    // affine map keeps the ray's parameter t.
    // On the stack: this runs once per primary ray.
    let mut spans = [None; MAX_VOLUMES];
    for (span, g) in spans.iter_mut().zip(&field.grids) {
        let (o, d) = (g.plan.grid(origin), g.plan.grid_direction(dir));
        *span = enter_exit(o, d, Vec3::ZERO, g.plan.last_vertex(), clip);
    }
    let union = spans.iter().flatten().fold(None, |u, &(a, b)| match u {
        None => Some((a, b)),
        Some((lo, hi)) => Some((a.min(lo), b.max(hi))),
    });
    let range = union.and_then(|r| clip_to_planes(r, origin, dir, &plan.clip_planes));
    if let Some((t0, t1)) = range {
        let len = t1 - t0;
        // `as` saturates; the cap holds where t has lost its precision.
        let n = ((len / plan.step).ceil() as u32).min(plan.max_steps);
        let mut k = 0;
        // Up to here, the last look at the bricks said some could show.
        let mut busy_until = f32::NEG_INFINITY;
        while k < n {
            // Every segment is a full step but the last; each is sampled
            // at its midpoint and its opacity corrected for its length.
            let start = k as f32 * plan.step;
            k += 1;
            let seg = plan.step.min(len - start).max(0.0);
            let t = t0 + start + 0.5 * seg;
            let p = origin + dir * t;
            if plan.skipping && t >= busy_until {
                let region = field.region(&spans, p, dir, t);
                if region.clear {
                    // Samples up to t + length are clear: go on from the
                    // last one at or before it (`as` saturates an endless
                    // leap).
                    let last_clear = ((t + region.length - t0) / plan.step - 0.5).floor();
                    k = k.max(last_clear as u32);
                    continue;
                }
                busy_until = t + region.length;
            }
            let mut mixture = Mixture::default();
            for (grid, span) in field.grids.iter().zip(&spans) {
                let Some((a, b)) = *span else { continue };
                if t < a || t > b {
                    continue;
                }
                samples += 1;
                let c = grid.classify(grid.sample(grid.plan.grid(p)));
                if c.w > 0.0 {
                    let a = correct(c.w, seg * grid.plan.inv_unit_distance);
                    mixture.add(c.truncate(), a);
                }
            }
            if mixture.is_empty() {
                continue;
            }
            let s = shade(field, p, &mut samples);
            let weight = (1.0 - acc.w) * mixture.alpha;
            acc = (acc.truncate() + mixture.color() * s * plan.light_color * weight)
                .extend(acc.w + weight);
            if depth == f32::INFINITY && acc.w >= plan.depth_threshold {
                depth = match rays.eye {
                    Some(eye) => (p - eye).length(),
                    None => t,
                };
            }
            if acc.w >= plan.termination {
                break;
            }
        }
    }
    let rgb = acc.truncate() + (1.0 - acc.w) * bg.truncate();
    RayResult {
        color: rgb.extend(acc.w + (1.0 - acc.w) * bg.w),
        depth,
        samples,
    }
}

/// Where a ray enters and leaves the box, clipped to the camera's
/// `(near, far)` (`near` >= 0).
pub(super) fn enter_exit(
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

/// The part of `(t0, t1)` on the kept side of every clip plane (n, d):
/// dot(n, o + t dir) < d.
pub(super) fn clip_to_planes(
    (mut t0, mut t1): (f32, f32),
    o: Vec3,
    dir: Vec3,
    planes: &[Vec4],
) -> Option<(f32, f32)> {
    for plane in planes {
        let n = plane.truncate();
        let (along, at) = (n.dot(dir), plane.w - n.dot(o));
        if along > 0.0 {
            t1 = t1.min(at / along);
        } else if along < 0.0 {
            t0 = t0.max(at / along);
        } else if at <= 0.0 {
            return None;
        }
    }
    (t1 > t0).then_some((t0, t1))
}

/// Light factor of the sample at `p` under the plan's shading mode.
fn shade(field: &Field, p: Vec3, samples: &mut u32) -> f32 {
    let plan = field.plan;
    let shadow = |samples: &mut u32| {
        let t = transmittance(field, p, plan.light, SHADOW_STEPS, samples);
        SHADOW_AMBIENT + (1.0 - SHADOW_AMBIENT) * t
    };
    let ao = |samples: &mut u32| {
        let mut occluded = 0.0;
        for &d in &plan.directions {
            occluded += field.opacity(p + d * plan.ao_radius, None, samples);
        }
        1.0 - occluded / plan.directions.len() as f32
    };
    match plan.shading {
        Shading::None | Shading::Directional(0) => 1.0,
        Shading::Shadows => shadow(samples),
        Shading::Ao => ao(samples),
        Shading::ShadowsAo => shadow(samples) * ao(samples),
        Shading::Directional(n) => {
            let mut sum = 0.0;
            for &d in &plan.directions {
                sum += transmittance(field, p, d, DIRECTIONAL_STEPS, samples);
            }
            sum / n as f32
        }
    }
}

/// Transmittance over up to `steps` shading steps from `p` along `dir`,
/// ending where the ray leaves every volume.
fn transmittance(field: &Field, p: Vec3, dir: Vec3, steps: u32, samples: &mut u32) -> f32 {
    let step = field.plan.shading_step;
    let mut t = 1.0;
    for k in 1..=steps {
        let q = p + dir * (step * k as f32);
        if !field.inside(q) {
            break;
        }
        t *= 1.0 - field.opacity(q, Some(step), samples);
    }
    t
}
