//! Sort-last compositing: every rank's partial image of its region
//! (premultiplied linear RGBA over a clear background) blended front to
//! back per pixel, in the order the pixel's ray enters the regions, then
//! over the frame's background. The regions are convex and disjoint, so
//! that order is the order of the samples along the ray, and the result is
//! the image one renderer would make of the whole: `over` is associative.
//! With direct-send each of N ranks composites one band of rows.

use std::ops::Range;

use glam::Vec4;

use super::region::Region;
use crate::geometry::RayGen;

/// One rank's partial image of a band of rows: premultiplied linear RGBA,
/// four floats a pixel, lower-left first.
#[derive(Clone, Copy)]
pub struct Partial<'a> {
    pub region: &'a Region,
    pub color: &'a [f32],
}

/// Rows `rows` of a frame `width` wide (the rays of `rays`): the partials
/// front to back over `background` (straight RGBA), as linear color the
/// renderers would have written. Each partial holds exactly those rows.
pub fn composite(
    rays: &RayGen,
    width: u32,
    rows: Range<u32>,
    partials: &[Partial<'_>],
    background: Vec4,
) -> Result<Vec<f32>, String> {
    let pixels = width as usize * rows.len();
    if let Some(p) = partials.iter().find(|p| p.color.len() != 4 * pixels) {
        return Err(format!(
            "a partial image has {} numbers where {width} x {} pixels need {}",
            p.color.len(),
            rows.len(),
            4 * pixels
        ));
    }
    let mut out = Vec::new();
    out.try_reserve_exact(4 * pixels)
        .map_err(|_| format!("no memory for {pixels} composited pixels"))?;
    let mut order: Vec<(f32, usize)> = Vec::with_capacity(partials.len());
    for y in rows {
        for x in 0..width {
            let at = out.len();
            order.clear();
            for (i, p) in partials.iter().enumerate() {
                if p.color[at..at + 4].iter().any(|&c| c != 0.0) {
                    order.push((f32::INFINITY, i));
                }
            }
            if order.len() > 1 {
                let (o, d) = rays.pixel_ray(x, y);
                for (t, i) in order.iter_mut() {
                    *t = partials[*i].region.entry(o, d).unwrap_or(f32::INFINITY);
                }
                order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            }
            let mut acc = Vec4::ZERO;
            for &(_, i) in &order {
                let c = Vec4::from_slice(&partials[i].color[at..at + 4]);
                acc += (1.0 - acc.w) * c;
            }
            let c = acc.truncate() + (1.0 - acc.w) * background.truncate();
            out.extend_from_slice(&c.extend(acc.w + (1.0 - acc.w) * background.w).to_array());
        }
    }
    Ok(out)
}

/// Direct-send's messages from one rank: band j of its partial image of a
/// frame `width` wide (four floats a pixel), for rank j of `ranks`, as
/// little-endian bytes.
pub fn bands_of(partial: &[f32], width: u32, ranks: usize) -> Vec<Vec<u8>> {
    let row = 4 * width as usize;
    let height = (partial.len() / row.max(1)) as u32;
    (0..ranks)
        .map(|j| {
            let rows = band(height, ranks, j);
            partial[row * rows.start as usize..row * rows.end as usize]
                .iter()
                .flat_map(|f| f.to_le_bytes())
                .collect()
        })
        .collect()
}

/// The floats of a message `bands_of` made.
pub fn floats_of(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// The rows rank `rank` of `ranks` composites under direct-send: bands as
/// even as whole rows allow, in rank order.
pub fn band(height: u32, ranks: usize, rank: usize) -> Range<u32> {
    let at = |r: usize| (u64::from(height) * r as u64 / ranks.max(1) as u64) as u32;
    at(rank)..at(rank + 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn partials_blend_in_the_order_rays_enter_their_regions() {
        // Two unit boxes one behind the other along z, seen from either end.
        let near = Region::world(Vec3::ZERO, Vec3::ONE).unwrap_or_else(|| panic!());
        let far = Region::world(Vec3::Z, Vec3::new(1.0, 1.0, 2.0)).unwrap_or_else(|| panic!());
        let red = [0.5, 0.0, 0.0, 0.5];
        let blue = [0.0, 0.0, 0.8, 0.8];
        let look = |from: f32, dir: f32| RayGen {
            origin: Vec3::new(0.5, 0.5, from),
            direction: Vec3::new(0.0, 0.0, dir),
            ..RayGen::default()
        };
        let parts = [
            Partial {
                region: &far,
                color: &blue,
            },
            Partial {
                region: &near,
                color: &red,
            },
        ];
        let bg = Vec4::new(0.0, 1.0, 0.0, 1.0);
        let from_front = composite(&look(-1.0, 1.0), 1, 0..1, &parts, bg).unwrap_or_default();
        // Red first: 0.5 + 0.5 * (0, 0, 0.8) then 0.1 of the background.
        let expect = [0.5, 0.1, 0.4, 1.0];
        for (a, b) in from_front.iter().zip(expect) {
            assert!((a - b).abs() < 1e-6, "{from_front:?}");
        }
        let from_back = composite(&look(3.0, -1.0), 1, 0..1, &parts, bg).unwrap_or_default();
        let expect = [0.1, 0.1, 0.8, 1.0];
        for (a, b) in from_back.iter().zip(expect) {
            assert!((a - b).abs() < 1e-6, "{from_back:?}");
        }
        let short = [Partial {
            region: &near,
            color: &red[..3],
        }];
        assert!(composite(&look(-1.0, 1.0), 1, 0..1, &short, bg).is_err());
    }

    #[test]
    fn a_partials_bands_travel_as_bytes_and_back() {
        let partial: Vec<f32> = (0..4 * 3 * 5).map(|i| i as f32 * 0.5).collect();
        let bands = bands_of(&partial, 3, 2);
        assert_eq!(bands.len(), 2);
        // Rows 0-1 to rank 0, rows 2-4 to rank 1.
        assert_eq!(floats_of(&bands[0]), partial[..24]);
        assert_eq!(floats_of(&bands[1]), partial[24..]);
    }

    #[test]
    fn bands_cover_the_rows_once() {
        for (h, n) in [(10, 4), (3, 4), (1080, 16), (7, 1)] {
            let bands: Vec<_> = (0..n).map(|r| band(h, n, r)).collect();
            assert_eq!(bands[0].start, 0);
            assert_eq!(bands[n - 1].end, h);
            for w in bands.windows(2) {
                assert_eq!(w[0].end, w[1].start);
            }
        }
    }
}
