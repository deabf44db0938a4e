//! A grid cut into bricks, one per rank of a data-parallel job: the cells
//! shared out evenly along the axes where they are longest, each brick
//! owning the cells between its two cut planes and storing one more vertex
//! beyond each cut (the apron), so that filters and gradients at its faces
//! read what the whole grid would.

use glam::UVec3;

/// One brick: where it sits among the bricks, the vertices whose cells it
/// owns, and the vertices it stores (the owned ones and the apron).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Brick {
    pub index: UVec3,
    /// First and last vertex of the owned cells; neighbours share the
    /// vertices of their common face.
    pub owned: (UVec3, UVec3),
    /// First and last vertex stored: `owned` and one more across every
    /// face inside the grid.
    pub stored: (UVec3, UVec3),
}

/// A grid of `dims` vertices cut into `counts` bricks, x fastest.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Split {
    pub dims: UVec3,
    pub counts: UVec3,
    pub bricks: Vec<Brick>,
}

impl Split {
    /// `dims` cut into `parts` bricks: each prime factor of `parts`, the
    /// largest first, cuts the axis whose bricks are then longest in cells,
    /// z before y before x where they tie (a z cut keeps a brick's voxels
    /// contiguous in a file, so that a rank reads only its pages).
    /// Refused where the grid has too few cells for that many bricks.
    pub fn new(dims: UVec3, parts: usize) -> Result<Self, String> {
        let cells = dims.saturating_sub(UVec3::ONE).max(UVec3::ONE);
        if parts == 0 {
            return Err("a volume is split into at least one brick".into());
        }
        let mut counts = UVec3::ONE;
        for p in prime_factors(parts).into_iter().rev() {
            let p = u32::try_from(p).map_err(|_| format!("{parts} bricks are too many"))?;
            let axis = (0..3)
                .filter(|&a| counts[a].saturating_mul(p) <= cells[a])
                .max_by(|&a, &b| {
                    let length = |a: usize| f64::from(cells[a]) / f64::from(counts[a] * p);
                    length(a).total_cmp(&length(b)).then(a.cmp(&b))
                })
                .ok_or_else(|| {
                    format!(
                        "a grid of {}x{}x{} vertices has too few cells for {parts} bricks",
                        dims.x, dims.y, dims.z
                    )
                })?;
            counts[axis] *= p;
        }
        let cut = |axis: usize, k: u32| -> u32 {
            (u64::from(k) * u64::from(cells[axis]) / u64::from(counts[axis])) as u32
        };
        let last = dims.saturating_sub(UVec3::ONE);
        let mut bricks = Vec::with_capacity(parts);
        for z in 0..counts.z {
            for y in 0..counts.y {
                for x in 0..counts.x {
                    let index = UVec3::new(x, y, z);
                    let lo = UVec3::new(cut(0, x), cut(1, y), cut(2, z));
                    let hi = UVec3::new(cut(0, x + 1), cut(1, y + 1), cut(2, z + 1)).min(last);
                    bricks.push(Brick {
                        index,
                        owned: (lo, hi),
                        stored: (lo.saturating_sub(UVec3::ONE), (hi + UVec3::ONE).min(last)),
                    });
                }
            }
        }
        Ok(Self {
            dims,
            counts,
            bricks,
        })
    }
}

fn prime_factors(mut n: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let mut p = 2;
    while p * p <= n {
        while n.is_multiple_of(p) {
            out.push(p);
            n /= p;
        }
        p += 1;
    }
    if n > 1 {
        out.push(n);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bricks_tile_the_cells_once_with_one_vertex_of_apron() {
        for (dims, parts) in [
            (UVec3::new(64, 64, 64), 4),
            (UVec3::new(200, 30, 10), 6),
            (UVec3::new(17, 9, 33), 12),
            (UVec3::new(5, 5, 5), 1),
            (UVec3::new(2, 2, 9), 8),
        ] {
            let split = Split::new(dims, parts).unwrap_or_else(|e| panic!("{dims}: {e}"));
            assert_eq!(split.bricks.len(), parts);
            assert_eq!(
                split.counts.x * split.counts.y * split.counts.z,
                parts as u32
            );
            let cells = dims - UVec3::ONE;
            let mut owned = 0u64;
            for b in &split.bricks {
                let (lo, hi) = b.owned;
                assert!(lo.cmplt(hi).all(), "{dims} {parts}: {b:?} owns no cell");
                owned += (hi - lo).as_u64vec3().element_product();
                for a in 0..3 {
                    let inner_lo = lo[a] > 0;
                    let inner_hi = hi[a] < cells[a];
                    assert_eq!(b.stored.0[a], lo[a] - u32::from(inner_lo));
                    assert_eq!(b.stored.1[a], hi[a] + u32::from(inner_hi));
                }
            }
            assert_eq!(owned, cells.as_u64vec3().element_product());
        }
    }

    #[test]
    fn the_longest_axis_is_cut_first_and_too_many_bricks_are_refused() {
        let split = Split::new(UVec3::new(256, 64, 32), 4).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(split.counts, UVec3::new(4, 1, 1));
        let split = Split::new(UVec3::new(64, 64, 64), 4).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(split.counts, UVec3::new(1, 2, 2));
        let err = Split::new(UVec3::new(3, 2, 2), 5).err();
        assert_eq!(
            err.as_deref(),
            Some("a grid of 3x2x2 vertices has too few cells for 5 bricks")
        );
        assert!(Split::new(UVec3::new(8, 8, 8), 0).is_err());
    }
}
