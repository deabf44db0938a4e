use glam::{IVec3, Vec3, Vec4};

use super::packet::{PacketGrid, Steps};
use super::sample::{correct, Field, MeshRays, Mixture};
use crate::geometry::{enter_exit, RayGen};
use crate::render::empty_space::{Along, EmptySpace};
use crate::render::march_plan::MarchPlan;
use crate::render::settings::{Shading, DIRECTIONAL_STEPS, SHADOW_AMBIENT, SHADOW_STEPS};
use crate::render::warp::LayerBuilder;
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
/// each sample mixing the volumes whose span holds it. With `layers`, every
/// contributing sample is also recorded there (the scalar path only: a
/// field without packets). The march ends at `stop`, where an opaque
/// surface of color `bg` hides what lies behind.
pub(super) fn march(
    field: &Field,
    rays: &RayGen,
    origin: Vec3,
    dir: Vec3,
    (bg, stop): (Vec4, f32),
    layers: Option<&mut LayerBuilder>,
) -> RayResult {
    let mut acc = Accumulator::new();
    let samples = march_segment(
        field,
        rays,
        (origin, dir),
        (rays.t_near, stop),
        &mut acc,
        layers,
    );
    RayResult {
        color: acc.over(bg),
        depth: acc.depth,
        samples,
    }
}

/// The march of one stretch `(start, stop)` of the ray `origin + t dir`,
/// composited behind what `acc` holds (a translucent surface's segments
/// follow one another); returns the samples taken. The stretch's steps
/// begin where its volumes do, as a march from `start` would.
pub(super) fn march_segment(
    field: &Field,
    rays: &RayGen,
    (origin, dir): (Vec3, Vec3),
    (start, stop): (f32, f32),
    acc: &mut Accumulator,
    mut layers: Option<&mut LayerBuilder>,
) -> u32 {
    let mut samples = 0;
    let plan = field.plan;
    // Surfaces alone: nothing to march between them (and a ray's mesh
    // state, set up below, would be made and dropped per pixel).
    if acc.color.w >= plan.termination || (field.grids.is_empty() && plan.part.is_none()) {
        return 0;
    }
    let clip = (start.max(rays.t_near), rays.t_far.min(stop));
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
    // A data-parallel part lays its steps along the whole's span.
    let laid = match &plan.part {
        Some(part) => part.whole_span(origin, dir, clip),
        None => union,
    };
    let range = laid.and_then(|r| clip_to_planes(r, origin, dir, &plan.clip_planes));
    // On the packet path (one trilinear volume) the ray's grid point is
    // go + gd t, and its bricks need no span checks.
    let one = field.packet.as_ref().map(|grid| {
        let g = &field.grids[0];
        let gd = g.plan.grid_direction(dir);
        OneVolume {
            grid,
            lanes: grid.lanes() as u32,
            go: g.plan.grid(origin),
            gd,
            along: Along::new(gd),
            hi: g.plan.dims.as_ivec3() - IVec3::ONE,
            space: g.space,
            exponent: plan.step * g.plan.inv_unit_distance,
        }
    });
    // What the bricks say from t on.
    let look = |t: f32| match one.as_ref().and_then(|o| Some((o, o.space?))) {
        Some((o, space)) => space.region(o.go + o.gd * t, &o.along, o.hi),
        None => field.region(&spans, origin + dir * t, dir, t),
    };
    let unlit = !plan.shading.lights();
    let mut meshes = MeshRays::new(field, origin, dir);
    if let Some((t0, t1)) = range {
        let len = t1 - t0;
        // `as` saturates; the cap holds where t has lost its precision.
        let n = (len / plan.step).ceil() as u32;
        // A part takes its share of the whole's steps, as many at most as
        // a ray takes (its index into them may be past that).
        let (mut k, n) = match &plan.part {
            Some(part) => part.owned_steps((origin, dir), (t0, len, n), plan.step),
            None => (0, n),
        };
        let n = n.min(k.saturating_add(plan.max_steps));
        // Up to here, the last look at the bricks said some could show.
        let mut busy_until = f32::NEG_INFINITY;
        'ray: while k < n {
            // Every segment is a full step but the last; each is sampled
            // at its midpoint and its opacity corrected for its length.
            // As march_plan::sample_t, which parts split the steps by.
            let start = k as f32 * plan.step;
            let seg = plan.step.min(len - start).max(0.0);
            let t = t0 + start + 0.5 * seg;
            let p = origin + dir * t;
            if plan.skipping && t >= busy_until {
                let region = look(t);
                if region.clear {
                    // Samples up to t + length are clear: go on from the
                    // last one at or before it (`as` saturates an endless
                    // leap).
                    let last_clear = ((t + region.length - t0) / plan.step - 0.5).floor();
                    k = (k + 1).max(last_clear as u32);
                    continue;
                }
                // Packets find clear space themselves (below): only one in
                // which nothing showed, before a clear brick, brings the
                // next look.
                busy_until = if one.is_some() {
                    f32::INFINITY
                } else {
                    t + region.length
                };
            }
            // Full steps, a packet's lanes at a time.
            if let Some(o) = one.as_ref().filter(|o| k + o.lanes < n) {
                // Lane 0's t is this step's.
                let steps = Steps {
                    t0,
                    k,
                    step: plan.step,
                };
                let classified = o.grid.classify(o.go, o.gd, steps, o.exponent);
                if !classified.any {
                    // Nothing showed: if the next sample's brick is clear,
                    // look for a leap there.
                    let next = steps.t(o.lanes as usize - 1) + plan.step;
                    if o.space
                        .is_some_and(|s| s.clear_at(o.go + o.gd * next, o.hi))
                    {
                        busy_until = f32::NEG_INFINITY;
                    }
                    k += o.lanes;
                    samples += o.lanes;
                    continue;
                }
                if unlit {
                    // Without shading the lanes composite at once.
                    let depth_at = if acc.depth == f32::INFINITY {
                        plan.depth_threshold
                    } else {
                        f32::INFINITY
                    };
                    let c = classified.composite(
                        acc.color,
                        plan.light_color,
                        plan.termination,
                        depth_at,
                    );
                    acc.color = c.acc;
                    if let Some(l) = c.depth_lane {
                        let t = steps.t(l);
                        acc.depth = rays.depth_at(origin + dir * t, t);
                    }
                    k += c.used as u32;
                    samples += c.used as u32;
                    if c.used < o.lanes as usize || acc.color.w >= plan.termination {
                        break 'ray;
                    }
                    continue;
                }
                let lanes = classified.alpha.into_iter().take(o.lanes as usize);
                for (l, a) in lanes.enumerate() {
                    k += 1;
                    samples += 1;
                    if a > 0.0 {
                        let t = steps.t(l);
                        let p = origin + dir * t;
                        let s = shade(field, p, &mut samples);
                        let lit = classified.color(l) * s * plan.light_color;
                        if acc.add(plan, rays, p, t, lit, a) {
                            break 'ray;
                        }
                    }
                }
                continue;
            }
            k += 1;
            let mut mixture = Mixture::default();
            for (v, (grid, span)) in field.grids.iter().zip(&spans).enumerate() {
                let Some((a, b)) = *span else { continue };
                if t < a || t > b {
                    continue;
                }
                samples += 1;
                let c = grid.classify(meshes.sample(field, v, p, t));
                if c.w > 0.0 {
                    let a = correct(c.w, seg * grid.plan.inv_unit_distance);
                    mixture.add(c.truncate(), a);
                }
            }
            if mixture.is_empty() {
                continue;
            }
            if !unlit {
                meshes.keep(field);
            }
            let s = shade(field, p, &mut samples);
            let lit = mixture.color() * s * plan.light_color;
            let opaque = acc.add(plan, rays, p, t, lit, mixture.alpha);
            if let Some(layers) = layers.as_deref_mut() {
                layers.add(t, seg, lit, mixture.alpha, acc.color.w);
            }
            if opaque {
                break;
            }
        }
    }
    meshes.keep(field);
    samples
}

/// Front-to-back compositing of one ray, and where it became opaque
/// enough for its depth.
pub(super) struct Accumulator {
    /// Premultiplied.
    pub color: Vec4,
    pub depth: f32,
}

impl Accumulator {
    pub fn new() -> Self {
        Self {
            color: Vec4::ZERO,
            depth: f32::INFINITY,
        }
    }

    /// What it holds over the straight color `bg`.
    pub fn over(&self, bg: Vec4) -> Vec4 {
        let c = self.color;
        (c.truncate() + (1.0 - c.w) * bg.truncate()).extend(c.w + (1.0 - c.w) * bg.w)
    }

    /// Adds a sample at `p` (`t` along the ray) of shaded color `lit` and
    /// opacity `a`; true once the ray is opaque enough to stop.
    pub fn add(
        &mut self,
        plan: &MarchPlan,
        rays: &RayGen,
        p: Vec3,
        t: f32,
        lit: Vec3,
        a: f32,
    ) -> bool {
        let acc = self.color;
        let weight = (1.0 - acc.w) * a;
        self.color = (acc.truncate() + lit * weight).extend(acc.w + weight);
        if self.depth == f32::INFINITY && self.color.w >= plan.depth_threshold {
            self.depth = rays.depth_at(p, t);
        }
        self.color.w >= plan.termination
    }
}

/// The one trilinear volume of the packet path, seen from one ray.
struct OneVolume<'a> {
    grid: &'a PacketGrid<'a>,
    /// Samples per packet.
    lanes: u32,
    /// The ray's grid point at t = 0 and its change per unit t.
    go: Vec3,
    gd: Vec3,
    along: Along,
    hi: IVec3,
    space: Option<&'a EmptySpace>,
    /// Unit distances in a full step (the opacity correction's exponent).
    exponent: f32,
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
            let blocked = 1.0 - field.surfaces_pass(p, d, plan.ao_radius);
            occluded +=
                blocked + (1.0 - blocked) * field.opacity(p + d * plan.ao_radius, None, samples);
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
/// ending where the ray leaves every volume, through the first surface in
/// its way.
fn transmittance(field: &Field, p: Vec3, dir: Vec3, steps: u32, samples: &mut u32) -> f32 {
    let step = field.plan.shading_step;
    let mut t = field.surfaces_pass(p, dir, step * steps as f32);
    if t <= 0.0 {
        return 0.0;
    }
    for k in 1..=steps {
        let q = p + dir * (step * k as f32);
        if !field.inside(q) {
            break;
        }
        t *= 1.0 - field.opacity(q, Some(step), samples);
    }
    t
}
