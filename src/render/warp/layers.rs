//! The emission-absorption layer representation (Lochmann et al., as
//! Buchacher's thesis adapts it for warping): each pixel's ray cut into
//! at most k segments where its accumulated opacity crosses j/k, each
//! segment one constant absorption and emission over its depth range, and
//! the re-march that shows them from another eye.

use glam::{Vec2, Vec3, Vec4};

use super::project::Projector;
use super::{Source, WarpSettings};
use crate::geometry::enter_exit;
use crate::geometry::RayGen;

/// The most layers a pixel may keep.
pub const MAX_LAYERS: usize = 8;

/// A surface's layer at least this opaque is opaque.
pub const SOLID: f32 = 0.999_999;

/// How deep a surface's layer is in a scene of box `(lo, hi)`: a
/// ten-thousandth of its diagonal, far thinner than a warp's re-march
/// step, so that one step takes it whole, as it would the surface.
pub fn surface_layer_depth((lo, hi): (Vec3, Vec3)) -> f32 {
    let depth = 1e-4 * (hi - lo).length();
    if depth.is_finite() && depth > 0.0 {
        depth
    } else {
        f32::MIN_POSITIVE
    }
}

/// One segment of a source ray: where it starts and ends (distances along
/// the unit ray from its origin) and what it shows on its own
/// (premultiplied color, opacity).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Layer {
    pub start: f32,
    pub end: f32,
    pub color: Vec4,
    /// It holds one surface alone, met at `end`: a re-march takes it
    /// whole where it crosses that point, since a layer that thin falls
    /// between the steps of a ray that crosses from one source pixel to
    /// the next.
    pub surface: bool,
}

impl Layer {
    /// Absorption per unit length and emitted color per unit opacity: the
    /// constants that, integrated from `start` to `end`, give `color`.
    fn coefficients(&self) -> (f32, Vec3) {
        let len = self.end - self.start;
        let a = self.color.w.min(0.999_999);
        if a <= 0.0 || len <= 0.0 {
            return (0.0, Vec3::ZERO);
        }
        (-(1.0 - a).ln() / len, self.color.truncate() / a)
    }
}

/// Collects one ray's contributing samples into layers while it marches.
/// A surface takes a layer of its own where one is left (blended into a
/// volume's layer it would spread its opacity over that layer's depth),
/// `surface_depth` deep and ending where the ray meets it.
#[derive(Clone, Copy, Debug)]
pub struct LayerBuilder {
    k: usize,
    current: usize,
    layers: [Layer; MAX_LAYERS],
    surface_depth: f32,
    /// Whether the next sample starts a layer of its own (after a
    /// surface).
    sealed: bool,
}

impl LayerBuilder {
    /// A builder for `k` layers (1..=MAX_LAYERS), surfaces
    /// `surface_depth` deep.
    pub fn new(k: usize, surface_depth: f32) -> Self {
        Self {
            k: k.clamp(1, MAX_LAYERS),
            current: 0,
            layers: [Layer::default(); MAX_LAYERS],
            surface_depth,
            sealed: false,
        }
    }

    /// A sample at `t` covering `seg` along the ray, shaded color `lit`
    /// and opacity `a`, after which the ray's opacity is `total`.
    pub fn add(&mut self, t: f32, seg: f32, lit: Vec3, a: f32, total: f32) {
        if std::mem::take(&mut self.sealed) {
            self.open();
        }
        self.keep((t - 0.5 * seg, t + 0.5 * seg), lit, a, total, false);
    }

    /// A surface met at `t`, shaded `lit`, of opacity `a` (1: the opaque
    /// one that ends the ray), after which the ray's opacity is `total`.
    pub fn add_surface(&mut self, t: f32, lit: Vec3, a: f32, total: f32) {
        self.open();
        self.keep((t - self.surface_depth, t), lit, a, total, true);
        self.sealed = true;
    }

    /// Moves on to the next layer if the current one holds anything and
    /// one is left.
    fn open(&mut self) {
        if self.layers[self.current].color.w > 0.0 && self.current + 1 < self.k {
            self.current += 1;
        }
    }

    fn keep(&mut self, (from, to): (f32, f32), lit: Vec3, a: f32, total: f32, surface: bool) {
        let layer = &mut self.layers[self.current];
        if layer.color.w == 0.0 {
            (layer.start, layer.end, layer.surface) = (from, to, surface);
        } else {
            layer.end = layer.end.max(to);
            layer.surface = false;
        }
        let weight = (1.0 - layer.color.w) * a;
        layer.color += (lit * weight).extend(weight);
        let threshold = (self.current + 1) as f32 / self.k as f32;
        if total >= threshold && self.current + 1 < self.k {
            self.current += 1;
        }
    }

    /// The `k` layers, unused ones empty.
    pub fn layers(&self) -> &[Layer] {
        &self.layers[..self.k]
    }
}

/// Re-marches target pixel (x, y)'s ray through the source's layers in
/// the settings' steps between where it enters and leaves the scene: every step
/// midpoint is projected into the source, and the layer of the source ray
/// there that holds it absorbs and emits over the step. Returns
/// premultiplied color and the depth where the opacity first reached
/// the settings' depth threshold.
pub(super) fn march(
    source: &Source,
    from: &Projector,
    rays: &RayGen,
    x: u32,
    y: u32,
    settings: &WarpSettings,
) -> (Vec4, f32) {
    let (o, d) = rays.pixel_ray(x, y);
    let (lo, hi) = settings.bounds;
    let Some((t0, t1)) = enter_exit(o, d, lo, hi, (rays.t_near, rays.t_far)) else {
        return (Vec4::ZERO, f32::INFINITY);
    };
    let steps = settings.layer_steps;
    let step = (t1 - t0) / steps as f32;
    let mut acc = Vec4::ZERO;
    let mut depth = f32::INFINITY;
    // Where the previous step's stretch ended: surfaces between there and
    // this step's end are crossed now (from the first step's start).
    let mut since = f32::INFINITY;
    for i in 0..steps {
        let t = t0 + (i as f32 + 0.5) * step;
        let p = o + d * t;
        let Some(seen) = from.locate(p) else {
            continue;
        };
        // The step covers this stretch of the source ray (its length
        // scaled by the rays' cosine).
        let c = d.dot(seen.direction).abs().max(1e-3);
        let (lo, hi) = (seen.along - 0.5 * step * c, seen.along + 0.5 * step * c);
        let crossed = since.min(lo);
        since = hi;
        // The step through the four source pixels around the point,
        // blended bilinearly as the quad warp blends colors.
        let q = seen.at - Vec2::splat(0.5);
        let base = q.floor();
        let f = q - base;
        let through = |dx: f32, dy: f32| {
            let px = base + Vec2::new(dx, dy);
            let inside = px.cmpge(Vec2::ZERO).all() && px.cmplt(source.size.as_vec2()).all();
            match inside.then(|| source.layers_at(px.as_uvec2())).flatten() {
                Some(layers) => through_layers(layers, (crossed, lo, hi), c),
                None => Vec4::ZERO,
            }
        };
        let bottom = through(0.0, 0.0).lerp(through(1.0, 0.0), f.x);
        let top = through(0.0, 1.0).lerp(through(1.0, 1.0), f.x);
        let s = bottom.lerp(top, f.y);
        if s.w <= 0.0 {
            continue;
        }
        acc += (1.0 - acc.w) * s;
        if depth == f32::INFINITY && acc.w >= settings.depth_threshold {
            depth = rays.depth_at(p, t);
        }
        if acc.w >= 0.99 {
            break;
        }
    }
    (acc, depth)
}

/// Premultiplied color and opacity of the stretch [lo, hi] of a source
/// ray with `layers`, for a target step `c` times longer than it:
/// each overlapping layer absorbs and emits over its share, front to back,
/// integrated exactly; a surface's layer counts whole where the ray
/// crossed it since `crossed`, an opaque one also where it lies within a
/// stretch's length before this one (the four source pixels' blend may
/// take a part of it at one step; the next takes the rest).
fn through_layers(layers: &[Layer], (crossed, lo, hi): (f32, f32, f32), c: f32) -> Vec4 {
    let mut s = Vec4::ZERO;
    for layer in layers {
        let (a, emitted) = if layer.surface {
            let a = layer.color.w.min(1.0);
            let since = if a >= SOLID {
                crossed.min(2.0 * lo - hi)
            } else {
                crossed
            };
            let met = layer.end <= hi && layer.end > since;
            if !met || a <= 0.0 {
                continue;
            }
            (a, layer.color.truncate() / a)
        } else {
            let overlap = (layer.end.min(hi) - layer.start.max(lo)) / c;
            if overlap <= 0.0 {
                continue;
            }
            let (sigma, emitted) = layer.coefficients();
            (1.0 - (-sigma * overlap).exp(), emitted)
        };
        let weight = (1.0 - s.w) * a;
        s += (emitted * weight).extend(weight);
    }
    s
}
