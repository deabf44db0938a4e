//! Empty-space skipping, exact: a grid of bricks holding the range of the
//! values each brick's samples can read, and per transfer function the
//! chessboard distance (in bricks) from every brick to the nearest one
//! whose range the table can make visible. A ray at an invisible brick
//! leaps to the edge of the cube of bricks that distance says is clear,
//! so it takes the same samples as a full march wherever anything shows
//! (docs/empty_space.md). Both renderers use these numbers; the shader's
//! `brick_region` finds the same regions as `EmptySpace::region`.

use std::sync::Arc;

use glam::{IVec3, UVec3, Vec3, Vec4};

use super::march_plan::MarchPlan;
use super::RenderError;
use crate::render::frame::filled;
use crate::scene::{
    AmrVolume, NanoVdbGrid, Scene, SpatialField, TransferFunction, UnstructuredVolume, TABLE_SIZE,
};

/// Cells per brick edge.
pub const BRICK: u32 = 8;
/// The largest distance kept: rays leap at most this many bricks at a
/// time, then look again.
pub const MAX_DISTANCE: u8 = 255;
/// How far, in grid units, a leap stops short of the clear region's edge,
/// so that rounding in the sample position never carries a ray past a
/// sample that could be visible.
pub const LEAP_MARGIN: f32 = 0.01;

/// Brick ranges per grid and clear bricks per grid and table, kept while
/// scenes bring the same `Arc`s: both renderers hold one.
#[derive(Debug, Default)]
pub(crate) struct SpaceCache {
    ranges: Vec<(Arc<SpatialField>, Arc<BrickRanges>)>,
    spaces: Vec<(Arc<SpatialField>, Arc<TransferFunction>, Arc<EmptySpace>)>,
}

impl SpaceCache {
    /// Forgets what belongs to grids `scene` does not hold.
    pub fn retain(&mut self, scene: &Scene) {
        let held = |v: &Arc<SpatialField>| scene.grids().any(|g| Arc::ptr_eq(g, v));
        self.ranges.retain(|(v, _)| held(v));
        self.spaces.retain(|(v, ..)| held(v));
    }

    /// The brick ranges of `volume`, made where they are new (and kept
    /// until an update leaves the volume out).
    pub fn ranges_of(
        &mut self,
        volume: &Arc<SpatialField>,
    ) -> Result<Arc<BrickRanges>, RenderError> {
        if let Some((_, r)) = self.ranges.iter().find(|(v, _)| Arc::ptr_eq(v, volume)) {
            return Ok(Arc::clone(r));
        }
        let ranges = Arc::new(BrickRanges::of_field(volume)?);
        self.ranges.push((Arc::clone(volume), Arc::clone(&ranges)));
        Ok(ranges)
    }

    /// The clear bricks of each of the scene's volumes, in its order,
    /// made only where the grid or the table is new (keeping no others),
    /// and whether they differ from the last call's.
    pub fn update(
        &mut self,
        scene: &Scene,
        plan: &MarchPlan,
    ) -> Result<(Vec<Arc<EmptySpace>>, bool), RenderError> {
        let mut next = Self::default();
        for (placed, vplan) in scene.volumes().iter().zip(&plan.volumes) {
            let (volume, tf) = (&placed.volume, &placed.transfer_function);
            let known = next
                .ranges
                .iter()
                .chain(&self.ranges)
                .find(|(v, _)| Arc::ptr_eq(v, volume))
                .map(|(_, r)| Arc::clone(r));
            let ranges = match known {
                Some(r) => r,
                None => Arc::new(BrickRanges::of_field(volume)?),
            };
            let known = next
                .spaces
                .iter()
                .chain(&self.spaces)
                .find(|(v, t, _)| Arc::ptr_eq(v, volume) && Arc::ptr_eq(t, tf))
                .map(|(.., s)| Arc::clone(s));
            let space = match known {
                Some(s) => s,
                None => Arc::new(EmptySpace::new(
                    &ranges,
                    &tf.table(),
                    vplan.value_lo,
                    vplan.value_scale,
                )?),
            };
            next.ranges.push((Arc::clone(volume), ranges));
            next.spaces
                .push((Arc::clone(volume), Arc::clone(tf), Arc::clone(&space)));
        }
        let changed = next.spaces.len() != self.spaces.len()
            || next
                .spaces
                .iter()
                .zip(&self.spaces)
                .any(|((.., a), (.., b))| !Arc::ptr_eq(a, b));
        *self = next;
        let spaces = self.spaces.iter().map(|(.., s)| Arc::clone(s)).collect();
        Ok((spaces, changed))
    }
}

/// Per brick, the smallest and largest value any sample in it reads. A
/// sample in cell i (vertices i..=i+1 per axis) lies in brick i / BRICK;
/// so brick b covers vertices BRICK*b ..= BRICK*(b+1), clamped to the grid.
#[derive(Clone, Debug, PartialEq)]
pub struct BrickRanges {
    pub bricks: UVec3,
    ranges: Vec<[f32; 2]>,
}

impl BrickRanges {
    /// `value(i)`: voxel i of a grid of `dims`, x fastest.
    pub fn new(dims: UVec3, value: impl Fn(usize) -> f32) -> Result<Self, RenderError> {
        let bricks = bricks_of(dims);
        let count = bricks.x as usize * bricks.y as usize * bricks.z as usize;
        let mut ranges = filled(
            count,
            [f32::INFINITY, f32::NEG_INFINITY],
            "the brick ranges",
        )?;
        let d = [dims.x, dims.y, dims.z].map(|v| v as usize);
        let b = BRICK as usize;
        // One pass over the voxels: each vertex widens every brick whose
        // vertex range holds it (a vertex on a brick face belongs to two).
        for z in 0..d[2] {
            let bz = owners(z, b, bricks.z as usize);
            for y in 0..d[1] {
                let by = owners(y, b, bricks.y as usize);
                let row = (z * d[1] + y) * d[0];
                for x in 0..d[0] {
                    let v = value(row + x);
                    if v.is_nan() {
                        // A NaN sample classifies to nothing: it widens
                        // no range.
                        continue;
                    }
                    let bx = owners(x, b, bricks.x as usize);
                    for kz in bz.clone() {
                        for ky in by.clone() {
                            let base = (kz * bricks.y as usize + ky) * bricks.x as usize;
                            for kx in bx.clone() {
                                let r = &mut ranges[base + kx];
                                r[0] = r[0].min(v);
                                r[1] = r[1].max(v);
                            }
                        }
                    }
                }
            }
        }
        Ok(Self { bricks, ranges })
    }

    /// The ranges of a field's bricks on its lattice: a grid's from its
    /// voxels, a mesh's or an AMR field's from its cells.
    pub fn of_field(field: &SpatialField) -> Result<Self, RenderError> {
        match field {
            SpatialField::Structured(v) => Self::new(v.dims(), |i| v.value(i)),
            SpatialField::Unstructured(m) => Self::of_mesh(m),
            SpatialField::Amr(a) => Self::of_amr(a),
            SpatialField::NanoVdb(g) => Self::of_nanovdb(g),
        }
    }

    /// Each cell widens every brick its box reaches on the mesh's
    /// lattice; bricks no cell reaches stay empty (clear under any table).
    pub fn of_mesh(mesh: &UnstructuredVolume) -> Result<Self, RenderError> {
        let (dims, spacing) = mesh.lattice();
        // A cell holds points a hair outside its box (CELL_TOLERANCE),
        // hence the margin.
        Self::of_boxes((dims, mesh.bounds().0, spacing), 0.01, mesh.cell_ranges())
    }

    /// Each cell widens every lattice brick its tent reaches (AMR
    /// units); bricks no tent reaches stay empty.
    pub fn of_amr(amr: &AmrVolume) -> Result<Self, RenderError> {
        let lattice = (amr.lattice().0, amr.amr_bounds().0, amr.lattice_step());
        Self::of_boxes(lattice, 0.0, amr.cell_ranges())
    }

    /// The tree's leaves and tiles, and the background, each widen the
    /// lattice bricks a sample of theirs can reach: a sample reads the
    /// voxels around it, one beyond the box it lies in.
    pub fn of_nanovdb(grid: &NanoVdbGrid) -> Result<Self, RenderError> {
        let lattice = (grid.lattice().0, Vec3::ZERO, Vec3::ONE);
        Self::of_boxes(lattice, 1.0, grid.value_boxes().into_iter())
    }

    /// Ranges of values over boxes (in the units of the lattice's
    /// `origin` and `spacing`), each widening every brick it reaches
    /// (`margin` lattice cells beyond it).
    fn of_boxes(
        (dims, origin, spacing): (UVec3, Vec3, Vec3),
        margin: f32,
        boxes: impl Iterator<Item = ((Vec3, Vec3), (f32, f32))>,
    ) -> Result<Self, RenderError> {
        let bricks = bricks_of(dims);
        let count = bricks.x as usize * bricks.y as usize * bricks.z as usize;
        let mut ranges = filled(
            count,
            [f32::INFINITY, f32::NEG_INFINITY],
            "the brick ranges",
        )?;
        let last = bricks.as_ivec3() - IVec3::ONE;
        // A sample at lattice point g reads brick floor(g / BRICK).
        let brick = |p: Vec3, margin: f32| {
            let g = (p - origin) / spacing + Vec3::splat(margin);
            (g / BRICK as f32)
                .floor()
                .as_ivec3()
                .clamp(IVec3::ZERO, last)
        };
        for ((lo, hi), (a, b)) in boxes {
            let (b0, b1) = (brick(lo, -margin), brick(hi, margin));
            for z in b0.z..=b1.z {
                for y in b0.y..=b1.y {
                    let row = (z as usize * bricks.y as usize + y as usize) * bricks.x as usize;
                    for x in b0.x..=b1.x {
                        let r = &mut ranges[row + x as usize];
                        r[0] = r[0].min(a);
                        r[1] = r[1].max(b);
                    }
                }
            }
        }
        Ok(Self { bricks, ranges })
    }

    pub fn range(&self, i: usize) -> [f32; 2] {
        self.ranges[i]
    }

    /// The range of every brick holding a vertex of `lo..hi` (a box of
    /// the grid's vertices): all a sample there can read, and perhaps a
    /// little more.
    pub fn covering(&self, lo: UVec3, hi: UVec3) -> [f32; 2] {
        let last = self.bricks - UVec3::ONE;
        let b0 = (lo.saturating_sub(UVec3::ONE) / BRICK).min(last);
        let b1 = (hi.saturating_sub(UVec3::ONE) / BRICK).min(last);
        let mut out = [f32::INFINITY, f32::NEG_INFINITY];
        for z in b0.z..=b1.z {
            for y in b0.y..=b1.y {
                for x in b0.x..=b1.x {
                    let i = (x + self.bricks.x * (y + self.bricks.y * z)) as usize;
                    let [a, b] = self.ranges[i];
                    out = [out[0].min(a), out[1].max(b)];
                }
            }
        }
        out
    }
}

/// Bricks per axis of a grid of `dims` vertices (dims - 1 cells).
fn bricks_of(dims: UVec3) -> UVec3 {
    (dims.max(UVec3::splat(2)) - UVec3::ONE).map(|c| c.div_ceil(BRICK))
}

/// The bricks whose vertex range holds vertex `v`: v / b, and v / b - 1
/// when v is on a face between two.
fn owners(v: usize, b: usize, n: usize) -> std::ops::Range<usize> {
    let hi = (v / b).min(n - 1);
    let lo = if v.is_multiple_of(b) && v > 0 {
        v / b - 1
    } else {
        hi
    };
    lo..hi + 1
}

/// Which value ranges a transfer function can make visible, as both
/// renderers classify (value -> (value - lo) * scale in [0, 1]).
pub(crate) struct Visibility {
    /// Entries below i with opacity above zero: any in a range of entries
    /// shows as a difference.
    visible_before: [u32; TABLE_SIZE + 1],
    value_lo: f32,
    value_scale: f32,
}

impl Visibility {
    /// `table`: the transfer function's TABLE_SIZE entries.
    pub fn new(table: &[Vec4], value_lo: f32, value_scale: f32) -> Self {
        debug_assert_eq!(table.len(), TABLE_SIZE);
        let mut visible_before = [0u32; TABLE_SIZE + 1];
        for (i, c) in table.iter().enumerate() {
            visible_before[i + 1] = visible_before[i] + u32::from(c.w > 0.0);
        }
        Self {
            visible_before,
            value_lo,
            value_scale,
        }
    }

    /// Whether a sample whose value lies in `lo..=hi` (interpolated
    /// between values in that range) could be visible; an empty range
    /// (lo > hi: every value NaN) never is.
    pub fn shows(&self, lo: f32, hi: f32) -> bool {
        if lo > hi {
            return false;
        }
        let last = (TABLE_SIZE - 1) as f32;
        let t = |v: f32| ((v - self.value_lo) * self.value_scale).clamp(0.0, 1.0) * last;
        // Scale may be negative only in theory; order the ends.
        let (a, b) = (t(lo), t(hi));
        let (ta, tb) = (a.min(b), a.max(b));
        // A value at t reads entries floor(t) and floor(t) + 1 (at most
        // size - 2 and size - 1), the second with weight t - floor(t): so
        // t in ta..=tb reads floor(ta) up to ceil(tb), and a range at an
        // entry's own value (a constant region at the table's end) reads
        // that entry alone.
        let first = (ta as usize).min(TABLE_SIZE - 2);
        let last = (tb.ceil() as usize).min(TABLE_SIZE - 1);
        self.visible_before[last + 1] > self.visible_before[first]
    }
}

/// One volume under one transfer function: per brick, the chessboard
/// distance to the nearest brick a sample could be visible in (0: this
/// one), at most MAX_DISTANCE.
#[derive(Clone, Debug, PartialEq)]
pub struct EmptySpace {
    pub bricks: UVec3,
    /// u32, as the shader and the CPU's gathers read it.
    pub distance: Vec<u32>,
}

impl EmptySpace {
    /// `table`: the transfer function's TABLE_SIZE entries, classified as
    /// both renderers classify (value -> (value - lo) * scale in [0, 1]).
    pub fn new(
        ranges: &BrickRanges,
        table: &[Vec4],
        value_lo: f32,
        value_scale: f32,
    ) -> Result<Self, RenderError> {
        let visible = Visibility::new(table, value_lo, value_scale);
        let count = ranges.ranges.len();
        let mut distance = filled(count, MAX_DISTANCE, "the empty-space distances")?;
        for (d, &[lo, hi]) in distance.iter_mut().zip(&ranges.ranges) {
            if visible.shows(lo, hi) {
                *d = 0;
            }
        }
        chessboard(&mut distance, ranges.bricks);
        let mut wide = filled(count, 0u32, "the empty-space distances")?;
        for (w, &d) in wide.iter_mut().zip(&distance) {
            *w = u32::from(d);
        }
        Ok(Self {
            bricks: ranges.bricks,
            distance: wide,
        })
    }

    /// The region around grid point `g` (inside the grid, whose largest
    /// vertex is `hi`) whose state is known, and how far a ray going
    /// `along` stays in it: the cube of clear bricks around a clear brick,
    /// or the brick itself where it could show.
    #[inline]
    pub fn region(&self, g: Vec3, along: &Along, hi: IVec3) -> Region {
        let b = cell_of(g, hi) / BRICK as i32;
        let d = self.distance[self.index(b)] as i32;
        // Bricks b - r ..= b + r, all clear or this one alone: grid points
        // from BRICK * (b - r) up to (not including) BRICK * (b + r + 1).
        let r = (d - 1).max(0);
        let lo = ((b - IVec3::splat(r)) * BRICK as i32).as_vec3();
        let up = ((b + IVec3::splat(r + 1)) * BRICK as i32).as_vec3();
        // Rounding must never end a leap past a brick that could show, nor
        // end sampling before the brick is left (its next look would find
        // it again): a margin shortens the one and lengthens the other,
        // per axis, in grid units.
        let (mut clear, mut busy) = (f32::INFINITY, f32::INFINITY);
        for k in 0..3 {
            let room = if along.gd[k] > 0.0 {
                (up[k] - g[k]) * along.inv[k]
            } else if along.gd[k] < 0.0 {
                (lo[k] - g[k]) * along.inv[k]
            } else {
                continue;
            };
            clear = clear.min(room - along.margin[k]);
            busy = busy.min(room + along.margin[k]);
        }
        if d > 0 {
            Region {
                clear: true,
                length: clear.max(0.0),
            }
        } else {
            Region {
                clear: false,
                length: busy,
            }
        }
    }

    /// Whether the brick a sample at grid point `g` reads is clear.
    #[inline]
    pub fn clear_at(&self, g: Vec3, hi: IVec3) -> bool {
        self.distance[self.index(cell_of(g, hi) / BRICK as i32)] > 0
    }

    fn index(&self, b: IVec3) -> usize {
        let n = self.bricks.as_ivec3();
        (b.x + n.x * (b.y + n.y * b.z)) as usize
    }
}

/// A ray's direction in a grid, with what every look at the bricks
/// divides by worked out once.
#[derive(Clone, Copy, Debug)]
pub struct Along {
    /// Grid units per unit t.
    gd: Vec3,
    inv: Vec3,
    /// LEAP_MARGIN grid units, in t, per axis.
    margin: Vec3,
}

impl Along {
    pub fn new(gd: Vec3) -> Self {
        let inv = gd.recip();
        Self {
            gd,
            inv,
            margin: LEAP_MARGIN * inv.abs(),
        }
    }
}

/// A stretch of a ray from a sample on: all clear (leap over it) or not
/// (sample every step of it), for `length` units of t.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    pub clear: bool,
    pub length: f32,
}

/// The cell a sample at grid point `g` interpolates in, as both
/// renderers choose it.
#[inline]
pub fn cell_of(g: Vec3, hi: IVec3) -> IVec3 {
    // Truncation is floor for the clamped, non-negative g.
    let g = g.clamp(Vec3::ZERO, hi.as_vec3());
    g.as_ivec3().min((hi - IVec3::ONE).max(IVec3::ZERO))
}

/// Turns 0 (occupied) / MAX_DISTANCE (clear) into the chessboard distance
/// to the nearest 0, capped at MAX_DISTANCE: two raster passes over the
/// 26-neighbourhood, which is exact for this metric.
fn chessboard(distance: &mut [u8], n: UVec3) {
    let n = n.as_ivec3();
    let index = |p: IVec3| (p.x + n.x * (p.y + n.y * p.z)) as usize;
    let inside = |p: IVec3| p.cmpge(IVec3::ZERO).all() && p.cmplt(n).all();
    for forward in [true, false] {
        let s = if forward { 1 } else { -1 };
        for zi in 0..n.z {
            for yi in 0..n.y {
                for xi in 0..n.x {
                    let p = if forward {
                        IVec3::new(xi, yi, zi)
                    } else {
                        n - IVec3::ONE - IVec3::new(xi, yi, zi)
                    };
                    let mut best = distance[index(p)];
                    if best == 0 {
                        continue;
                    }
                    // The 13 neighbours already visited in this pass.
                    for dz in -1..=0 {
                        for dy in -1..=1 {
                            for dx in -1..=1 {
                                let before = dz < 0 || (dz == 0 && (dy < 0 || (dy == 0 && dx < 0)));
                                if !before {
                                    continue;
                                }
                                let q = p + IVec3::new(dx, dy, dz) * s;
                                if inside(q) {
                                    best = best.min(distance[index(q)].saturating_add(1));
                                }
                            }
                        }
                    }
                    distance[index(p)] = best;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bricks any sample could be visible in.
    fn occupied(space: &EmptySpace) -> usize {
        space.distance.iter().filter(|&&d| d == 0).count()
    }

    fn brute_force(occupied: &[bool], n: UVec3) -> Vec<u8> {
        let n = n.as_ivec3();
        let mut out = Vec::new();
        for z in 0..n.z {
            for y in 0..n.y {
                for x in 0..n.x {
                    let p = IVec3::new(x, y, z);
                    let mut best = i32::from(MAX_DISTANCE);
                    for (i, &o) in occupied.iter().enumerate() {
                        if o {
                            let i = i as i32;
                            let q = IVec3::new(i % n.x, (i / n.x) % n.y, i / (n.x * n.y));
                            best = best.min((p - q).abs().max_element());
                        }
                    }
                    out.push(best as u8);
                }
            }
        }
        out
    }

    #[test]
    fn the_two_pass_transform_is_the_chessboard_distance() {
        let n = UVec3::new(7, 5, 6);
        let count = (n.x * n.y * n.z) as usize;
        let mut state = 12345u32;
        for density in [1, 5, 40] {
            let occupied: Vec<bool> = (0..count)
                .map(|_| {
                    state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                    (state >> 24) % 100 < density
                })
                .collect();
            let mut d: Vec<u8> = occupied
                .iter()
                .map(|&o| if o { 0 } else { MAX_DISTANCE })
                .collect();
            chessboard(&mut d, n);
            assert_eq!(d, brute_force(&occupied, n), "density {density}%");
        }
    }

    #[test]
    fn a_range_reads_the_entries_its_interpolation_weighs() {
        // Clear up to entry 10, visible from entry 11 on; values 0..=255
        // map to entries 0..=255.
        let table: Vec<Vec4> = (0..TABLE_SIZE)
            .map(|i| Vec4::new(1.0, 1.0, 1.0, if i > 10 { 0.5 } else { 0.0 }))
            .collect();
        let v = Visibility::new(&table, 0.0, 1.0 / 255.0);
        // A constant region at entry 10's own value reads entry 10 alone.
        assert!(!v.shows(10.0, 10.0));
        assert!(!v.shows(0.0, 10.0));
        // Past it, entry 11 weighs in.
        assert!(v.shows(10.0, 10.01));
        assert!(v.shows(10.5, 10.5));
        assert!(v.shows(0.0, 255.0));
    }

    #[test]
    fn a_brick_holds_the_values_on_its_faces() {
        // 17 vertices per axis: 16 cells, 2 bricks; vertex 8 is on both.
        let dims = UVec3::splat(17);
        let ranges = BrickRanges::new(dims, |i| if i % 17 == 8 { 1.0 } else { 0.0 }).unwrap();
        assert_eq!(ranges.bricks, UVec3::new(2, 2, 2));
        for i in 0..8 {
            assert_eq!(ranges.range(i), [0.0, 1.0]);
        }
        let ranges = BrickRanges::new(dims, |i| if i % 17 == 16 { 1.0 } else { 0.0 }).unwrap();
        assert_eq!(ranges.range(0), [0.0, 0.0]);
        assert_eq!(ranges.range(1), [0.0, 1.0]);
    }

    #[test]
    fn a_brick_is_empty_only_where_the_table_is_clear_over_its_range() {
        let dims = UVec3::splat(17);
        // Brick x = 0 holds values up to 0.25, brick x = 1 up to 0.75.
        let ranges = BrickRanges::new(dims, |i| {
            if i % 17 > 8 {
                0.75
            } else {
                0.25 * (i % 17 == 8) as u8 as f32
            }
        })
        .unwrap();
        let mut table = vec![Vec4::ZERO; TABLE_SIZE];
        // Visible from 0.5 on: brick 1 shows, brick 0 does not.
        for (i, c) in table.iter_mut().enumerate() {
            if i as f32 / (TABLE_SIZE - 1) as f32 >= 0.5 {
                c.w = 0.3;
            }
        }
        let space = EmptySpace::new(&ranges, &table, 0.0, 1.0).unwrap();
        assert_eq!(space.distance[0], 1);
        assert_eq!(space.distance[1], 0);
        // The entry beside a visible one counts: interpolation reads both.
        table[127].w = 0.0;
        table[128].w = 0.3;
        let space = EmptySpace::new(&ranges, &table, 0.0, 1.0).unwrap();
        assert_eq!(occupied(&space), 4);
        // Values below the table's range clamp to its clear first entry...
        let space = EmptySpace::new(&ranges, &table, 2.0, 1.0).unwrap();
        assert_eq!(occupied(&space), 0);
        // ... and above it to its visible last one.
        let space = EmptySpace::new(&ranges, &table, -2.0, 1.0).unwrap();
        assert_eq!(occupied(&space), 8);
    }

    #[test]
    fn a_leap_ends_before_the_first_brick_that_could_show() {
        let dims = UVec3::new(41, 9, 9); // 5 bricks along x, one across
        let ranges = BrickRanges::new(dims, |i| if i % 41 >= 32 { 1.0 } else { 0.0 }).unwrap();
        let mut table = vec![Vec4::ZERO; TABLE_SIZE];
        table[TABLE_SIZE - 1].w = 1.0;
        let space = EmptySpace::new(&ranges, &table, 0.0, 1.0).unwrap();
        // Vertex 32 belongs to bricks 3 and 4.
        assert_eq!(space.distance, vec![3, 2, 1, 0, 0]);
        let hi = dims.as_ivec3() - IVec3::ONE;
        let leap = |x: f32, gd: Vec3| {
            let r = space.region(Vec3::new(x, 4.0, 4.0), &Along::new(gd), hi);
            assert!(r.clear, "x = {x}");
            r.length
        };
        let t = leap(1.5, Vec3::new(2.0, 0.0, 0.0));
        // Clear up to x = 24 (bricks 0..=2), at 2 grid units per t.
        assert!((t - (24.0 - 1.5 - LEAP_MARGIN) / 2.0).abs() < 1e-5, "{t}");
        // Brick 3 could show: sampled up to just past its far face.
        let r = space.region(Vec3::new(25.0, 4.0, 4.0), &Along::new(Vec3::X), hi);
        assert!(!r.clear);
        assert!(
            (r.length - (32.0 - 25.0 + LEAP_MARGIN)).abs() < 1e-5,
            "{r:?}"
        );
        // Going away from the visible part: brick 2 alone is known clear
        // there, brick 1 sees to the grid's end.
        let t = leap(20.0, -Vec3::X);
        assert!((t - (4.0 - LEAP_MARGIN)).abs() < 1e-4, "{t}");
        let t = leap(12.0, -Vec3::X);
        assert!((t - (12.0 - LEAP_MARGIN)).abs() < 1e-4, "{t}");
    }
}
