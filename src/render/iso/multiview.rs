//! The display image of a multi-view display, every subpixel from its own
//! eye (issue 17): the naive way (every view rendered, then interleaved),
//! the per-subpixel way (one ray per subpixel, from its eye: the same
//! image, whatever the number of views), and a geometric pass plus a
//! spectral pass, which casts one channel's ray in full and finds the
//! other channels' hits near it, casting them in full only where their
//! eyes may see another surface.

use glam::UVec2;
use rayon::prelude::*;

use super::cast::{values, Caster, IsoHit};
use super::IsoSettings;
use crate::geometry::RayGen;
use crate::render::frame::filled;
use crate::render::{ColorFormat, Frame, FrameDesc, RenderError};
use crate::scene::PlacedVolume;

/// How the display image is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MultiViewMethod {
    /// Every view's whole image, then each subpixel from its view's.
    Naive,
    /// One ray a subpixel, from that subpixel's eye.
    PerSubpixel,
    /// The green channel's ray cast in full; red's and blue's searched from
    /// a little before green's hit, and cast in full only where a crossing
    /// may lie before that, or near an edge of the surface.
    GeometricSpectral,
}

impl MultiViewMethod {
    pub fn name(self) -> &'static str {
        match self {
            MultiViewMethod::Naive => "naive",
            MultiViewMethod::PerSubpixel => "per-subpixel",
            MultiViewMethod::GeometricSpectral => "geometric+spectral",
        }
    }
}

/// Steps before the geometric hit at which a spectral search starts.
pub(crate) const SEARCH_MARGIN_STEPS: f32 = 2.0;

/// The panel as the renderer sees it: each view's rays over the panel's
/// pixels, and which view each subpixel (x, y, channel) belongs to.
pub struct Panel<'a> {
    pub size: UVec2,
    /// The display image's pixel format.
    pub color: ColorFormat,
    pub views: Vec<RayGen>,
    pub view_of: &'a (dyn Fn(u32, u32, usize) -> u32 + Sync),
}

impl Panel<'_> {
    /// The view of subpixel `c` of pixel (x, y), within the views given.
    pub fn view(&self, x: u32, y: u32, c: usize) -> u32 {
        (self.view_of)(x, y, c).min(self.views.len().saturating_sub(1) as u32)
    }
}

/// The display image (RGBA, each of R, G and B from its subpixel's view;
/// lower-left first) and the field evaluations it took.
pub fn render_display(
    placed: &PlacedVolume,
    display: &Panel,
    settings: &IsoSettings,
    method: MultiViewMethod,
) -> Result<(Frame, u64), RenderError> {
    settings.validate()?;
    let values = values(placed)?;
    render_display_by(&Caster::new(placed, &values, settings), display, method)
}

/// `render_display` with a caster made beforehand (its settings checked).
pub fn render_display_by(
    caster: &Caster,
    display: &Panel,
    method: MultiViewMethod,
) -> Result<(Frame, u64), RenderError> {
    let size = display.size;
    let desc = FrameDesc::new(size).with_color(display.color);
    desc.validate()?;
    if display.views.is_empty() {
        return Err(RenderError::Settings(
            "a display needs at least one view".into(),
        ));
    }
    let rays = &display.views;
    let w = size.x as usize;
    let table = view_table(display)?;
    let mut rgb = filled(desc.pixels(), [0.0f32; 3], "the display image")?;
    let samples = match method {
        MultiViewMethod::Naive => {
            let mut total = 0;
            let mut views = Vec::with_capacity(rays.len());
            for r in rays {
                let (colours, n) = view_image(caster, r, size)?;
                total += n;
                views.push(colours);
            }
            for (i, px) in rgb.iter_mut().enumerate() {
                for (c, out) in px.iter_mut().enumerate() {
                    *out = views[table[i][c] as usize][i][c];
                }
            }
            total
        }
        MultiViewMethod::PerSubpixel => rgb
            .par_chunks_mut(w)
            .enumerate()
            .map(|(y, row)| {
                let mut n = 0;
                for (x, px) in row.iter_mut().enumerate() {
                    for (c, out) in px.iter_mut().enumerate() {
                        let r = &rays[table[y * w + x][c] as usize];
                        let (o, d) = r.pixel_ray(x as u32, y as u32);
                        let hit = caster.first_hit(o, d, (r.t_near, r.t_far), &mut n);
                        *out = caster.colour(hit.as_ref(), d)[c];
                    }
                }
                n
            })
            .sum(),
        MultiViewMethod::GeometricSpectral => {
            geometric_spectral(caster, &table, rays, size, &mut rgb)?
        }
    };
    // A panel shows no alpha.
    let mut color = filled(4 * desc.pixels(), 0.0f32, "the display image")?;
    for (o, px) in color.chunks_exact_mut(4).zip(&rgb) {
        o.copy_from_slice(&[px[0], px[1], px[2], 1.0]);
    }
    Ok((Frame::from_linear(&desc, color, None)?, samples))
}

/// Every subpixel's view, row by row from the lower left: the pattern's
/// function called once a subpixel, not once a use.
pub(crate) fn view_table(display: &Panel) -> Result<Vec<[u32; 3]>, RenderError> {
    let w = display.size.x as usize;
    let mut table = filled(w * display.size.y as usize, [0u32; 3], "the panel's views")?;
    table.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, views) in row.iter_mut().enumerate() {
            *views = [0, 1, 2].map(|c| display.view(x as u32, y as u32, c));
        }
    });
    Ok(table)
}

/// One view's whole image as linear RGB, and its field evaluations.
fn view_image(
    caster: &Caster,
    rays: &RayGen,
    size: UVec2,
) -> Result<(Vec<[f32; 3]>, u64), RenderError> {
    let w = size.x as usize;
    let mut out = filled(w * size.y as usize, [0.0f32; 3], "a view's image")?;
    let n = out
        .par_chunks_mut(w)
        .enumerate()
        .map(|(y, row)| {
            let mut n = 0;
            for (x, px) in row.iter_mut().enumerate() {
                let (o, d) = rays.pixel_ray(x as u32, y as u32);
                let hit = caster.first_hit(o, d, (rays.t_near, rays.t_far), &mut n);
                let c = caster.colour(hit.as_ref(), d);
                *px = [c.x, c.y, c.z];
            }
            n
        })
        .sum();
    Ok((out, n))
}

/// The geometric pass (green, in full) and the spectral pass (red and
/// blue, searched from where their own views' samples met the surface).
fn geometric_spectral(
    caster: &Caster,
    table: &[[u32; 3]],
    rays: &[RayGen],
    size: UVec2,
    rgb: &mut [[f32; 3]],
) -> Result<u64, RenderError> {
    let w = size.x as usize;
    let mut geometric: Vec<Option<IsoHit>> = filled(rgb.len(), None, "the geometric pass")?;
    let n_geometric: u64 = geometric
        .par_chunks_mut(w)
        .enumerate()
        .map(|(y, row)| {
            let mut n = 0;
            for (x, hit) in row.iter_mut().enumerate() {
                let r = &rays[table[y * w + x][1] as usize];
                let (o, d) = r.pixel_ray(x as u32, y as u32);
                *hit = caster.first_hit(o, d, (r.t_near, r.t_far), &mut n);
            }
            n
        })
        .sum();
    let h = size.y as usize;
    let margin = SEARCH_MARGIN_STEPS * caster.step;
    let reach = rays.len() + SAME_VIEW_SLACK;
    let n_spectral: u64 = rgb
        .par_chunks_mut(w)
        .enumerate()
        .map(|(y, row)| {
            let mut n = 0;
            for (x, px) in row.iter_mut().enumerate() {
                let i = y * w + x;
                let views = table[i];
                for (c, out) in px.iter_mut().enumerate() {
                    let r = &rays[views[c] as usize];
                    let (o, d) = r.pixel_ray(x as u32, y as u32);
                    let clip = (r.t_near, r.t_far);
                    let hit = if c == 1 || views[c] == views[1] {
                        // The geometric pass's very ray.
                        geometric[i]
                    } else {
                        let near =
                            SameView::around(&geometric, table, (w, h), (x, y), views[c], reach);
                        near.window(geometric[i].map(|g| g.t), margin)
                            .or_else(|| fallback_window(&geometric, (w, h), (x, y), margin))
                            .flatten()
                            .and_then(|window| {
                                caster
                                    .hit_between(o, d, clip, window, &mut n)
                                    .unwrap_or_else(|| caster.first_hit(o, d, clip, &mut n))
                            })
                    };
                    *out = caster.colour(hit.as_ref(), d)[c];
                }
            }
            n
        })
        .sum();
    Ok(n_geometric + n_spectral)
}

/// Pixels beyond the number of views that the search for a view's own
/// samples reaches along a row.
pub(crate) const SAME_VIEW_SLACK: usize = 2;

/// What the geometric pass saw of one view near a pixel: green's hits at
/// the nearest pixels left and right, in the pixel's row and the rows
/// above and below, whose green subpixel has that view. These are samples
/// of that view's own image, so they say where (and whether) the view's
/// ray through the pixel meets the surface.
struct SameView {
    /// Whether any such pixel lies within reach.
    seen: bool,
    /// The nearer of the two hits either side in the pixel's own row.
    bracket: Option<f32>,
    /// The nearest and farthest hit of all.
    range: Option<(f32, f32)>,
}

impl SameView {
    fn around(
        geometric: &[Option<IsoHit>],
        table: &[[u32; 3]],
        (w, h): (usize, usize),
        (x, y): (usize, usize),
        view: u32,
        reach: usize,
    ) -> Self {
        let mut near = SameView {
            seen: false,
            bracket: None,
            range: None,
        };
        for yy in y.saturating_sub(1)..(y + 2).min(h) {
            let t = |xx: usize| geometric[yy * w + xx].map(|g| g.t);
            let found = |xx: &usize| table[yy * w + xx][1] == view;
            let left = (x.saturating_sub(reach)..x).rev().find(found).map(t);
            let right = (x + 1..(x + 1 + reach).min(w)).find(found).map(t);
            if let (true, Some(Some(a)), Some(Some(b))) = (yy == y, left, right) {
                near.bracket = Some(a.min(b));
            }
            for t in [left, right].into_iter().flatten() {
                near.seen = true;
                if let Some(t) = t {
                    let (lo, hi) = near.range.unwrap_or((t, t));
                    near.range = Some((lo.min(t), hi.max(t)));
                }
            }
        }
        near
    }

    /// Where to search the view's ray (`Some(None)`: nowhere, it sees
    /// nothing), given green's hit at the pixel; `None` if no sample of the
    /// view lies within reach.
    fn window(&self, green: Option<f32>, margin: f32) -> Option<Option<(f32, f32)>> {
        if !self.seen {
            return None;
        }
        Some(match (self.range, green) {
            // From a little before the nearer of its neighbours' surfaces
            // (the two either side bracket it on a smooth surface), on.
            (Some((lo, _)), Some(_)) => Some((self.bracket.unwrap_or(lo) - margin, f32::INFINITY)),
            // Green missed, the view's neighbours did not: around their
            // surfaces.
            (Some((lo, hi)), None) => Some((lo - margin, hi + 3.0 * margin)),
            // The view's neighbours all missed: at most a surface near
            // green's.
            (None, Some(g)) => Some((g - margin, g + 3.0 * margin)),
            (None, None) => None,
        })
    }
}

/// Where to search without samples of the view (a panel narrower than a
/// pattern period): from before green's surface on, or where green
/// missed, around the nearest surface a neighbouring green saw.
fn fallback_window(
    geometric: &[Option<IsoHit>],
    (w, h): (usize, usize),
    (x, y): (usize, usize),
    margin: f32,
) -> Option<Option<(f32, f32)>> {
    if let Some(g) = geometric[y * w + x] {
        return Some(Some((g.t - margin, f32::INFINITY)));
    }
    let nearest = (y.saturating_sub(1)..(y + 2).min(h))
        .flat_map(|yy| (x.saturating_sub(1)..(x + 2).min(w)).map(move |xx| yy * w + xx))
        .filter_map(|j| geometric[j].map(|g| g.t))
        .reduce(f32::min);
    Some(nearest.map(|t| (t - margin, t + 3.0 * margin)))
}

/// The channel-by-channel difference of two display images, as the share
/// of subpixels that differ by more than `tolerance` (8-bit steps).
pub fn subpixels_differing(a: &Frame, b: &Frame, tolerance: u8) -> f64 {
    let (ra, rb) = (a.to_srgb8_top_down(), b.to_srgb8_top_down());
    let differ = ra
        .chunks_exact(4)
        .zip(rb.chunks_exact(4))
        .flat_map(|(p, q)| (0..3).map(move |c| p[c].abs_diff(q[c]) > tolerance))
        .filter(|&d| d)
        .count();
    differ as f64 / (3 * ra.len() / 4).max(1) as f64
}
