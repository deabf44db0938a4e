//! The display image of a multi-view display, every subpixel from its own
//! eye: the naive way (every view rendered, then interleaved),
//! the per-subpixel way (one ray per subpixel, from its eye: the same
//! image, whatever the number of views), and a geometric pass plus a
//! spectral pass, which casts one channel's ray in full and finds the
//! other channels' hits near it, casting them in full only where their
//! eyes may see another surface, or shades its hit for them.

use std::sync::Arc;

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
    /// The geometric pass, then red and blue shade green's hit as their own
    /// views' rays see it: one view's march, but a channel shows the colour
    /// of a point its eye does not see through that pixel.
    GreenGeometry,
}

impl MultiViewMethod {
    pub fn name(self) -> &'static str {
        match self {
            MultiViewMethod::Naive => "naive",
            MultiViewMethod::PerSubpixel => "per-subpixel",
            MultiViewMethod::GeometricSpectral => "geometric+spectral",
            MultiViewMethod::GreenGeometry => "green-geometry",
        }
    }

    /// Passes over the panel's rows, with `views` views.
    pub fn passes(self, views: usize) -> usize {
        match self {
            MultiViewMethod::Naive => views,
            MultiViewMethod::PerSubpixel => 1,
            MultiViewMethod::GeometricSpectral | MultiViewMethod::GreenGeometry => 2,
        }
    }
}

/// Steps before the geometric hit at which a spectral search starts.
pub(crate) const SEARCH_MARGIN_STEPS: f32 = 2.0;

/// The panel as the renderer sees it: each view's rays over the panel's
/// pixels, and which view each subpixel (x, y, channel) belongs to. The
/// views are looked up once, when the panel is made, not every frame.
pub struct Panel {
    pub size: UVec2,
    /// The display image's pixel format.
    pub color: ColorFormat,
    pub views: Vec<RayGen>,
    /// Every subpixel's view, row by row from the lower left.
    table: Arc<[[u32; 3]]>,
}

impl Panel {
    /// `view_of(x, y, channel)` gives each subpixel's view; views past the
    /// last are taken as the last.
    pub fn new(
        size: UVec2,
        color: ColorFormat,
        views: Vec<RayGen>,
        view_of: impl Fn(u32, u32, usize) -> u32 + Sync,
    ) -> Result<Self, RenderError> {
        // Sizes a frame could not have are refused before allocating.
        let desc = FrameDesc::new(size);
        desc.validate()?;
        let (w, pixels) = (size.x as usize, desc.pixels());
        let mut table = filled(pixels, [0u32; 3], "the panel's views")?;
        let last = views.len().saturating_sub(1) as u32;
        table.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                *px = [0, 1, 2].map(|c| view_of(x as u32, y as u32, c).min(last));
            }
        });
        Ok(Self {
            size,
            color,
            views,
            table: table.into(),
        })
    }

    /// A panel with another's views of each subpixel (a display's pattern
    /// stays from frame to frame), if they cover `size`.
    pub fn with_table(
        size: UVec2,
        color: ColorFormat,
        views: Vec<RayGen>,
        table: Arc<[[u32; 3]]>,
    ) -> Result<Self, RenderError> {
        let panel = Self {
            size,
            color,
            views,
            table,
        };
        panel.checked_table()?;
        if let Some(v) = panel
            .table
            .iter()
            .flatten()
            .find(|&&v| v as usize >= panel.views.len())
        {
            return Err(RenderError::Settings(format!(
                "a subpixel shows view {v} of a panel of {} views",
                panel.views.len()
            )));
        }
        Ok(panel)
    }

    /// The view of subpixel `c` of pixel (x, y).
    pub fn view(&self, x: u32, y: u32, c: usize) -> u32 {
        self.table[(y * self.size.x + x) as usize][c.min(2)]
    }

    /// Every subpixel's view, row by row from the lower left.
    pub fn table(&self) -> &Arc<[[u32; 3]]> {
        &self.table
    }

    /// The table, if it covers the panel's size (which is public).
    pub fn checked_table(&self) -> Result<&[[u32; 3]], RenderError> {
        let pixels = FrameDesc::new(self.size).pixels();
        if self.table.len() != pixels {
            return Err(RenderError::Settings(format!(
                "the panel's views cover {} pixels, not its {}x{}",
                self.table.len(),
                self.size.x,
                self.size.y
            )));
        }
        Ok(&self.table)
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
    let table = display.checked_table()?;
    let mut rgb = filled(desc.pixels(), [0.0f32; 3], "the display image")?;
    // Every pass's rows before the first starts, so that the fraction
    // done never falls back.
    caster.expect(method.passes(rays.len()) as u64 * u64::from(size.y));
    let samples = match method {
        MultiViewMethod::Naive => {
            let mut total = 0;
            let mut views = Vec::with_capacity(rays.len());
            for r in rays {
                let (colors, n) = view_image(caster, r, size)?;
                total += n;
                views.push(colors);
            }
            for (i, px) in rgb.iter_mut().enumerate() {
                for (c, out) in px.iter_mut().enumerate() {
                    *out = views[table[i][c] as usize][i][c];
                }
            }
            total
        }
        MultiViewMethod::PerSubpixel => caster.rows(&mut rgb, w, |y, row| {
            let mut n = 0;
            for (x, px) in row.iter_mut().enumerate() {
                for (c, out) in px.iter_mut().enumerate() {
                    let r = &rays[table[y * w + x][c] as usize];
                    let (o, d) = r.pixel_ray(x as u32, y as u32);
                    let hit = caster.first_hit(o, d, (r.t_near, r.t_far), &mut n);
                    *out = caster.color(hit.as_ref(), d)[c];
                }
            }
            n
        }),
        MultiViewMethod::GeometricSpectral => {
            geometric_spectral(caster, table, rays, size, &mut rgb)?
        }
        MultiViewMethod::GreenGeometry => green_geometry(caster, table, rays, size, &mut rgb)?,
    };
    caster.check_stop()?;
    // A panel shows no alpha.
    let mut color = filled(4 * desc.pixels(), 0.0f32, "the display image")?;
    for (o, px) in color.chunks_exact_mut(4).zip(&rgb) {
        o.copy_from_slice(&[px[0], px[1], px[2], 1.0]);
    }
    Ok((Frame::from_linear(&desc, color, None)?, samples))
}

/// One view's whole image as linear RGB, and its field evaluations.
fn view_image(
    caster: &Caster,
    rays: &RayGen,
    size: UVec2,
) -> Result<(Vec<[f32; 3]>, u64), RenderError> {
    let w = size.x as usize;
    let mut out = filled(w * size.y as usize, [0.0f32; 3], "a view's image")?;
    let n = caster.rows(&mut out, w, |y, row| {
        let mut n = 0;
        for (x, px) in row.iter_mut().enumerate() {
            let (o, d) = rays.pixel_ray(x as u32, y as u32);
            let hit = caster.first_hit(o, d, (rays.t_near, rays.t_far), &mut n);
            let c = caster.color(hit.as_ref(), d);
            *px = [c.x, c.y, c.z];
        }
        n
    });
    Ok((out, n))
}

/// The geometric pass: each pixel's green ray in full, its hit and the
/// field evaluations.
fn geometric_pass(
    caster: &Caster,
    table: &[[u32; 3]],
    rays: &[RayGen],
    size: UVec2,
) -> Result<(Vec<Option<IsoHit>>, u64), RenderError> {
    let w = size.x as usize;
    let mut geometric: Vec<Option<IsoHit>> = filled(table.len(), None, "the geometric pass")?;
    let n = caster.rows(&mut geometric, w, |y, row| {
        let mut n = 0;
        for (x, hit) in row.iter_mut().enumerate() {
            let r = &rays[table[y * w + x][1] as usize];
            let (o, d) = r.pixel_ray(x as u32, y as u32);
            *hit = caster.first_hit(o, d, (r.t_near, r.t_far), &mut n);
        }
        n
    });
    Ok((geometric, n))
}

/// The geometric pass, then every channel shading green's hit as its own
/// view's ray through the pixel sees it (the normal still faces green's
/// eye, as the hit was found).
fn green_geometry(
    caster: &Caster,
    table: &[[u32; 3]],
    rays: &[RayGen],
    size: UVec2,
    rgb: &mut [[f32; 3]],
) -> Result<u64, RenderError> {
    let w = size.x as usize;
    let (geometric, n) = geometric_pass(caster, table, rays, size)?;
    caster.rows(rgb, w, |y, row| {
        for (x, px) in row.iter_mut().enumerate() {
            let i = y * w + x;
            for (c, out) in px.iter_mut().enumerate() {
                let (_, d) = rays[table[i][c] as usize].pixel_ray(x as u32, y as u32);
                *out = caster.color(geometric[i].as_ref(), d)[c];
            }
        }
        0
    });
    Ok(n)
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
    let (geometric, n_geometric) = geometric_pass(caster, table, rays, size)?;
    let h = size.y as usize;
    let margin = SEARCH_MARGIN_STEPS * caster.step;
    let offsets = same_view_offsets();
    // Only where a channel's view is not green's is anything searched.
    let searched = table.iter().any(|v| v[0] != v[1] || v[2] != v[1]);
    let near = match searched {
        true => near_surface(&geometric, (w, h), SAME_VIEW_RADIUS as usize)?,
        false => Vec::new(),
    };
    let n_spectral: u64 = caster.rows(rgb, w, |y, row| {
        let mut n = 0;
        for (x, px) in row.iter_mut().enumerate() {
            let i = y * w + x;
            let views = table[i];
            let (_, green_d) = rays[views[1] as usize].pixel_ray(x as u32, y as u32);
            // Green's ray, and any channel of green's view, shade the
            // geometric pass's very hit, seen the same way.
            let green = caster.color(geometric[i].as_ref(), green_d);
            for (c, out) in px.iter_mut().enumerate() {
                if views[c] == views[1] {
                    *out = green[c];
                    continue;
                }
                let r = &rays[views[c] as usize];
                let (o, d) = r.pixel_ray(x as u32, y as u32);
                let clip = (r.t_near, r.t_far);
                let hit = if !near[i] {
                    // No green hit within the samples' reach: every
                    // window below would be empty.
                    None
                } else {
                    let samples =
                        SameView::around(&geometric, table, (w, h), (x, y), views[c], &offsets);
                    samples
                        .window(geometric[i].map(|g| g.t), margin)
                        .or_else(|| fallback_window(&geometric, (w, h), (x, y), margin))
                        .flatten()
                        .and_then(|window| {
                            caster
                                .hit_between(o, d, clip, window, &mut n)
                                .unwrap_or_else(|| caster.first_hit(o, d, clip, &mut n))
                        })
                };
                *out = caster.color(hit.as_ref(), d)[c];
            }
        }
        n
    });
    Ok(n_geometric + n_spectral)
}

/// How many of a view's samples, nearest first, bound a search of its ray.
pub(crate) const SAME_VIEW_SAMPLES: usize = 4;

/// How far (in pixels) from a subpixel its view's samples are looked for:
/// a slanted lens puts a view's pixels a few rows and columns apart.
pub(crate) const SAME_VIEW_RADIUS: i32 = 4;

/// The pixel offsets (dx, dy) within [`SAME_VIEW_RADIUS`] of a pixel,
/// itself left out, nearest first; ties by row, then column, so that the
/// GPU, which gets this list, looks in the same order.
pub(crate) fn same_view_offsets() -> Vec<(i32, i32)> {
    let r = SAME_VIEW_RADIUS;
    let mut offsets: Vec<(i32, i32)> = (-r..=r)
        .flat_map(|dy| (-r..=r).map(move |dx| (dx, dy)))
        .filter(|&(dx, dy)| (dx, dy) != (0, 0) && dx * dx + dy * dy <= r * r)
        .collect();
    offsets.sort_by_key(|&(dx, dy)| (dx * dx + dy * dy, dy, dx));
    offsets
}

/// Per pixel, whether the geometric pass hit anything within `r` pixels
/// across and up (a square, which holds every offset searched).
fn near_surface(
    geometric: &[Option<IsoHit>],
    (w, h): (usize, usize),
    r: usize,
) -> Result<Vec<bool>, RenderError> {
    // Along rows: pixels since the last hit to the left and until the next
    // to the right; then the same down columns.
    let mut rows = filled(w * h, false, "the surface's reach")?;
    for (hits, out) in geometric.chunks_exact(w).zip(rows.chunks_exact_mut(w)) {
        let mut since = usize::MAX;
        for (x, hit) in hits.iter().enumerate() {
            since = if hit.is_some() {
                0
            } else {
                since.saturating_add(1)
            };
            out[x] = since <= r;
        }
        since = usize::MAX;
        for (x, hit) in hits.iter().enumerate().rev() {
            since = if hit.is_some() {
                0
            } else {
                since.saturating_add(1)
            };
            out[x] |= since <= r;
        }
    }
    let mut near = filled(w * h, false, "the surface's reach")?;
    for x in 0..w {
        let mut since = usize::MAX;
        for y in 0..h {
            since = if rows[y * w + x] {
                0
            } else {
                since.saturating_add(1)
            };
            near[y * w + x] = since <= r;
        }
        since = usize::MAX;
        for y in (0..h).rev() {
            since = if rows[y * w + x] {
                0
            } else {
                since.saturating_add(1)
            };
            near[y * w + x] |= since <= r;
        }
    }
    Ok(near)
}

/// What the geometric pass saw of one view near a pixel: green's hits at
/// the [`SAME_VIEW_SAMPLES`] nearest pixels whose green subpixel has that
/// view. These are samples of that view's own image, so they say where
/// (and whether) the view's ray through the pixel meets the surface.
struct SameView {
    /// Whether any such pixel lies within reach.
    seen: bool,
    /// The nearest and farthest hit among them.
    range: Option<(f32, f32)>,
}

impl SameView {
    fn around(
        geometric: &[Option<IsoHit>],
        table: &[[u32; 3]],
        (w, h): (usize, usize),
        (x, y): (usize, usize),
        view: u32,
        offsets: &[(i32, i32)],
    ) -> Self {
        let mut near = SameView {
            seen: false,
            range: None,
        };
        let mut found = 0;
        for &(dx, dy) in offsets {
            let (xx, yy) = (x as i64 + i64::from(dx), y as i64 + i64::from(dy));
            if xx < 0 || yy < 0 || xx >= w as i64 || yy >= h as i64 {
                continue;
            }
            let j = yy as usize * w + xx as usize;
            if table[j][1] != view {
                continue;
            }
            near.seen = true;
            if let Some(g) = geometric[j] {
                let (lo, hi) = near.range.unwrap_or((g.t, g.t));
                near.range = Some((lo.min(g.t), hi.max(g.t)));
            }
            found += 1;
            if found == SAME_VIEW_SAMPLES {
                break;
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
            // From a little before the nearest of its samples' surfaces on.
            (Some((lo, _)), Some(_)) => Some((lo - margin, f32::INFINITY)),
            // Green missed, the view's samples did not: around their
            // surfaces.
            (Some((lo, hi)), None) => Some((lo - margin, hi + 3.0 * margin)),
            // The view's samples all missed: at most a surface near
            // green's.
            (None, Some(g)) => Some((g - margin, g + 3.0 * margin)),
            (None, None) => None,
        })
    }
}

/// Where to search without samples of the view within reach (views too
/// many for the radius, or a panel's edge): from before green's surface
/// on, or where green missed, around the nearest surface a neighbouring
/// green saw.
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_are_nearest_first_within_the_radius() {
        let offsets = same_view_offsets();
        let r2 = SAME_VIEW_RADIUS * SAME_VIEW_RADIUS;
        let d2 = |&(dx, dy): &(i32, i32)| dx * dx + dy * dy;
        assert!(offsets.windows(2).all(|w| d2(&w[0]) <= d2(&w[1])));
        assert!(offsets.iter().all(|o| (1..=r2).contains(&d2(o))));
        // Every pixel of the disc but the centre, once.
        let disc = (-SAME_VIEW_RADIUS..=SAME_VIEW_RADIUS)
            .flat_map(|dy| (-SAME_VIEW_RADIUS..=SAME_VIEW_RADIUS).map(move |dx| (dx, dy)))
            .filter(|o| d2(o) <= r2)
            .count();
        assert_eq!(offsets.len(), disc - 1);
        assert_eq!(offsets[..4], [(0, -1), (-1, 0), (1, 0), (0, 1)]);
    }

    #[test]
    fn near_surface_is_any_hit_in_the_square_around() {
        let (w, h, r) = (23usize, 17usize, 2usize);
        let hit = IsoHit {
            t: 1.0,
            position: glam::Vec3::ZERO,
            normal: glam::Vec3::Z,
            curvatures: (0.0, 0.0),
        };
        // A scatter of hits, deterministic.
        let geometric: Vec<Option<IsoHit>> = (0..w * h)
            .map(|i| ((i * 7919) % 61 == 0).then_some(hit))
            .collect();
        let near = near_surface(&geometric, (w, h), r).unwrap();
        for y in 0..h {
            for x in 0..w {
                let brute = (y.saturating_sub(r)..(y + r + 1).min(h)).any(|yy| {
                    (x.saturating_sub(r)..(x + r + 1).min(w))
                        .any(|xx| geometric[yy * w + xx].is_some())
                });
                assert_eq!(near[y * w + x], brute, "({x}, {y})");
            }
        }
        assert!(near.iter().any(|&n| n) && near.iter().any(|&n| !n));
    }

    #[test]
    fn a_panel_takes_only_a_table_that_fits_it() {
        let rays = vec![RayGen::default(); 2];
        let size = UVec2::new(3, 2);
        let panel = Panel::new(size, ColorFormat::default(), rays.clone(), |x, _, c| {
            x + c as u32
        })
        .unwrap();
        // Views past the last are the last.
        assert_eq!(panel.view(2, 1, 2), 1);
        assert_eq!(panel.view(0, 0, 0), 0);
        let short: Arc<[[u32; 3]]> = vec![[0, 1, 1]; 5].into();
        let e = Panel::with_table(size, ColorFormat::default(), rays.clone(), short)
            .err()
            .unwrap();
        assert!(e.to_string().contains("cover 5 pixels, not its 3x2"), "{e}");
        let beyond: Arc<[[u32; 3]]> = vec![[0, 2, 1]; 6].into();
        let e = Panel::with_table(size, ColorFormat::default(), rays.clone(), beyond)
            .err()
            .unwrap();
        assert!(
            e.to_string().contains("view 2 of a panel of 2 views"),
            "{e}"
        );
        let e = Panel::new(
            UVec2::new(0, 2),
            ColorFormat::default(),
            rays.clone(),
            |_, _, _| 0,
        )
        .err()
        .unwrap();
        assert!(e.to_string().contains("at least 1x1"), "{e}");
        let kept = Panel::with_table(size, ColorFormat::default(), rays, panel.table().clone());
        assert_eq!(kept.unwrap().table()[..], panel.table()[..]);
    }
}
