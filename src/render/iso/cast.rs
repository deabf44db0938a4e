//! The isosurface caster's march: fixed steps through the grid until the
//! field crosses the iso-value, then secant steps within that bracket.

use std::sync::atomic::AtomicBool;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::field::{crossing_box, curvatures, IsoField, IsoFilter};
use super::{curvature_color, Coloring, IsoSettings};
use crate::geometry::enter_exit;
use crate::geometry::RayGen;
use crate::render::frame::filled;
use crate::render::{Frame, FrameDesc, RenderError, Watch};
use crate::scene::PlacedVolume;

/// Where a ray meets the isosurface, and the surface there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IsoHit {
    /// Along the unit ray from its origin.
    pub t: f32,
    pub position: Vec3,
    /// Unit normal, facing the ray's origin.
    pub normal: Vec3,
    /// Principal curvatures, larger first, as the ray's origin sees the
    /// surface: positive where it bulges towards the eye. (0, 0) under
    /// trilinear filtering unless curvature colors the surface.
    pub curvatures: (f32, f32),
}

/// A volume's field ready for casting, with the march's step.
pub struct Caster<'a> {
    pub field: IsoField<'a>,
    pub step: f32,
    pub settings: &'a IsoSettings,
    /// The grid-space box outside which the field cannot cross the
    /// iso-value: rays march inside it only.
    pub bounds: (Vec3, Vec3),
    /// Its stop flag set by a discard or a release: the rows not yet cast
    /// are skipped, and the image is refused (`RenderError::Stopped`).
    /// Casts count rows into its progress.
    watch: Option<Watch<'a>>,
}

/// The volume's values as f32, which a [`Caster`] reads.
/// Why isosurface rendering refuses a mesh: it walks a grid's cells.
pub const UNSTRUCTURED_ISO: &str =
    "isosurfaces are drawn of structured fields only; this volume is an unstructured field";

pub fn values(placed: &PlacedVolume) -> Result<Vec<f32>, RenderError> {
    let Some(volume) = placed.volume.structured() else {
        return Err(RenderError::Settings(UNSTRUCTURED_ISO.into()));
    };
    let mut values = filled(volume.voxels().len(), 0.0f32, "the volume as f32")?;
    for (i, v) in values.iter_mut().enumerate() {
        *v = volume.value(i);
    }
    Ok(values)
}

impl<'a> Caster<'a> {
    pub fn new(placed: &PlacedVolume, values: &'a [f32], settings: &'a IsoSettings) -> Self {
        let dims = placed.volume.dims();
        let bounds = crossing_box(dims, |i| values[i], settings.isovalue, settings.filter);
        Self::with_bounds(placed, values, settings, bounds)
    }

    /// A caster whose crossing box (of these values, iso-value and
    /// filter) was found before.
    pub fn with_bounds(
        placed: &PlacedVolume,
        values: &'a [f32],
        settings: &'a IsoSettings,
        bounds: (Vec3, Vec3),
    ) -> Self {
        Self {
            field: IsoField::new(placed, values, settings.filter),
            step: placed.smallest_cell() / settings.steps_per_cell,
            settings,
            bounds,
            watch: None,
        }
    }

    /// The caster, stopping once `stop` is set.
    pub fn until(self, stop: &'a AtomicBool) -> Self {
        self.watched(Watch::new(stop))
    }

    /// The caster, stopping once the watch's stop flag is set and counting
    /// each row it finishes into its progress.
    pub fn watched(self, watch: Watch<'a>) -> Self {
        Self {
            watch: Some(watch),
            ..self
        }
    }

    /// Whether the cast was asked to stop: each row looks before it starts.
    pub fn stopped(&self) -> bool {
        self.watch.is_some_and(|w| w.stopped())
    }

    /// Announces a cast's rows, all its passes' together.
    pub(crate) fn expect(&self, rows: u64) {
        if let Some(w) = self.watch {
            w.expect(rows);
        }
    }

    /// One more row cast.
    pub(crate) fn row_done(&self) {
        if let Some(w) = self.watch {
            w.advance(1);
        }
    }

    /// `f(y, row)` over the rows of `data` (`width` items a row) in
    /// parallel, each row counted done; rows not yet started once the
    /// cast is stopped are skipped. Returns the sum of what `f` returns
    /// (field evaluations).
    pub(crate) fn rows<T: Send>(
        &self,
        data: &mut [T],
        width: usize,
        f: impl Fn(usize, &mut [T]) -> u64 + Sync,
    ) -> u64 {
        data.par_chunks_mut(width)
            .enumerate()
            .map(|(y, row)| {
                if self.stopped() {
                    return 0;
                }
                let n = f(y, row);
                self.row_done();
                n
            })
            .sum()
    }

    /// `Err(Stopped)` once the cast was asked to stop.
    pub fn check_stop(&self) -> Result<(), RenderError> {
        match self.stopped() {
            true => Err(RenderError::Stopped),
            false => Ok(()),
        }
    }

    /// The first crossing along `o + t d` within the grid and `clip`,
    /// counting field evaluations into `samples`.
    pub fn first_hit(
        &self,
        o: Vec3,
        d: Vec3,
        clip: (f32, f32),
        samples: &mut u64,
    ) -> Option<IsoHit> {
        let (go, gd) = self.field.grid_ray(o, d);
        let (t0, t1) = enter_exit(go, gd, self.bounds.0, self.bounds.1, clip)?;
        *samples += 1;
        let entry = self.field.value(go + gd * t0) - self.settings.isovalue;
        self.march(o, d, (t0, t1), (0, entry), u32::MAX, samples)
    }

    /// The first crossing in `from..until` along `o + t d`, if the ray is
    /// on the same side of the iso-value at `from` as where it enters the
    /// grid; `None` if it is not (a crossing lies before `from`). The
    /// search starts at the last of `first_hit`'s steps at or before
    /// `from`, so a crossing it finds is `first_hit`'s, to the bit.
    pub fn hit_between(
        &self,
        o: Vec3,
        d: Vec3,
        clip: (f32, f32),
        (from, until): (f32, f32),
        samples: &mut u64,
    ) -> Option<Option<IsoHit>> {
        let (go, gd) = self.field.grid_ray(o, d);
        let Some((t0, t1)) = enter_exit(go, gd, self.bounds.0, self.bounds.1, clip) else {
            return Some(None);
        };
        let iso = self.settings.isovalue;
        let k0 = self.steps_before(from - t0, t1 - t0);
        let start = t0 + k0 as f32 * self.step;
        *samples += 1;
        let entry = self.field.value(go + gd * t0) - iso;
        let there = if k0 == 0 {
            entry
        } else {
            *samples += 1;
            self.field.value(go + gd * start) - iso
        };
        if (entry < 0.0) != (there < 0.0) {
            return None;
        }
        let last = self.steps_before(until - t0, t1 - t0).saturating_add(1);
        Some(self.march(o, d, (t0, t1), (k0, there), last, samples))
    }

    /// Whole steps from the grid entry that fit in `length`, within `span`.
    fn steps_before(&self, length: f32, span: f32) -> u32 {
        (length.min(span) / self.step).floor().clamp(0.0, 1e6) as u32
    }

    /// The march over the span (`t0`, `t1`) from its step `k0`, where the
    /// field minus the iso-value is `fa`, to its step `last` at most.
    fn march(
        &self,
        o: Vec3,
        d: Vec3,
        (t0, t1): (f32, f32),
        (k0, mut fa): (u32, f32),
        last: u32,
        samples: &mut u64,
    ) -> Option<IsoHit> {
        let (go, gd) = self.field.grid_ray(o, d);
        let s = self.settings;
        let at = |t: f32| self.field.value(go + gd * t) - s.isovalue;
        let mut ta = t0 + k0 as f32 * self.step;
        let steps = ((t1 - t0) / self.step).ceil().min(1e6) as u32;
        for k in k0 + 1..=steps.min(last) {
            let tb = (t0 + k as f32 * self.step).min(t1);
            let fb = at(tb);
            *samples += 1;
            if fa == 0.0 || (fa < 0.0) != (fb < 0.0) {
                *samples += u64::from(s.secant_steps) + 1;
                let t = refine(&at, (ta, fa), (tb, fb), s.secant_steps);
                // The B-spline's Hessian comes with its gradient; the
                // trilinear one costs six gradients more, so only where
                // curvature colors the surface.
                let hessian = s.filter == IsoFilter::TricubicBSpline
                    || matches!(s.coloring, Coloring::Curvature { .. });
                let sample = self.field.sample_with(go + gd * t, hessian);
                let g = sample.gradient;
                let (k1, k2) = if hessian {
                    curvatures(g, sample.hessian)
                } else {
                    (0.0, 0.0)
                };
                let mut normal = -g.normalize_or_zero();
                // Seen from the other side, a bulge is a hollow.
                let mut curvatures = (k1, k2);
                if normal.dot(d) > 0.0 {
                    normal = -normal;
                    curvatures = (-k2, -k1);
                }
                return Some(IsoHit {
                    t,
                    position: o + d * t,
                    normal,
                    curvatures,
                });
            }
            (ta, fa) = (tb, fb);
        }
        None
    }

    /// The color of `hit` seen along `d`, or the background.
    pub fn color(&self, hit: Option<&IsoHit>, d: Vec3) -> Vec4 {
        match hit {
            Some(h) => shade(h, d, self.settings),
            None => self.settings.background,
        }
    }
}

/// Casts `rays` (an image of `desc.size`) at `placed`'s isosurface: the
/// shaded frame and each pixel's hit (lower-left first).
pub fn cast(
    placed: &PlacedVolume,
    rays: &RayGen,
    desc: &FrameDesc,
    settings: &IsoSettings,
) -> Result<(Frame, Vec<Option<IsoHit>>), RenderError> {
    settings.validate()?;
    let values = values(placed)?;
    cast_by(&Caster::new(placed, &values, settings), rays, desc)
}

/// `cast` with a caster made beforehand (its settings checked).
pub fn cast_by(
    caster: &Caster,
    rays: &RayGen,
    desc: &FrameDesc,
) -> Result<(Frame, Vec<Option<IsoHit>>), RenderError> {
    desc.validate()?;
    let (w, n) = (desc.size.x as usize, desc.pixels());
    let mut hits = filled(n, None, "the hits")?;
    caster.expect(u64::from(desc.size.y));
    caster.rows(&mut hits, w, |y, row| {
        let mut samples = 0;
        for (x, hit) in row.iter_mut().enumerate() {
            let (o, d) = rays.pixel_ray(x as u32, y as u32);
            *hit = caster.first_hit(o, d, (rays.t_near, rays.t_far), &mut samples);
        }
        samples
    });
    caster.check_stop()?;
    let mut color = filled(4 * n, 0.0f32, "the frame's color")?;
    let mut depth = filled(n, f32::INFINITY, "the frame's depth")?;
    for (i, hit) in hits.iter().enumerate() {
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        let (_, d) = rays.pixel_ray(x, y);
        if let Some(h) = hit {
            depth[i] = rays.depth_at(h.position, h.t);
        }
        color[4 * i..4 * i + 4].copy_from_slice(&caster.color(hit.as_ref(), d).to_array());
    }
    let frame = Frame::from_linear(desc, color, desc.depth.then_some(depth))?;
    Ok((frame, hits))
}

/// Secant (regula falsi) steps within a bracket whose ends differ in sign.
fn refine(
    at: &dyn Fn(f32) -> f32,
    (mut ta, mut fa): (f32, f32),
    (mut tb, mut fb): (f32, f32),
    steps: u32,
) -> f32 {
    if fa == 0.0 {
        return ta;
    }
    if steps == 0 {
        // The march alone: the first sample past the crossing.
        return tb;
    }
    for _ in 0..steps {
        let t = if fb != fa {
            ta - fa * (tb - ta) / (fb - fa)
        } else {
            0.5 * (ta + tb)
        };
        let ft = at(t);
        if ft == 0.0 {
            return t;
        }
        if (ft < 0.0) == (fa < 0.0) {
            (ta, fa) = (t, ft);
        } else {
            (tb, fb) = (t, ft);
        }
    }
    if fb != fa {
        ta - fa * (tb - ta) / (fb - fa)
    } else {
        0.5 * (ta + tb)
    }
}

/// Blinn-Phong shading of a hit seen along `d`.
fn shade(h: &IsoHit, d: Vec3, s: &IsoSettings) -> Vec4 {
    let base = match s.coloring {
        Coloring::Flat(c) => c,
        Coloring::Curvature { radius } => {
            curvature_color(0.5 * (h.curvatures.0 + h.curvatures.1), radius)
        }
    };
    let l = s.light.map_or(-d, |l| l.normalize());
    let half = (l - d).normalize_or_zero();
    let diffuse = h.normal.dot(l).max(0.0);
    let specular = h.normal.dot(half).max(0.0).powf(s.shininess);
    let rgb = base * (s.ambient + s.diffuse * diffuse) + Vec3::splat(s.specular * specular);
    rgb.min(Vec3::ONE).extend(1.0)
}
