//! Block-structured adaptive mesh refinement (AMR), as FLASH, Enzo,
//! AMReX and Chombo write it and hosts send it as ANARI's `amr` field:
//! levels of cell-centred grids, each level's cells `width` units wide,
//! blocks of cells at each level given by inclusive integer bounds in
//! their level's index space (cell i of a level spans [i w, (i + 1) w)).
//! Coarse blocks under fine ones are usually sent too.
//!
//! The cells are kept in bricks of 8x8x8 cells per level, found through
//! an open-addressing hash of (level, brick) shared word for word with
//! the GPU (gpu/amr.rs); a cell no block holds reads [`AMR_ABSENT`]. The
//! lowest mantissa bit of every present value says whether all 26
//! neighbours of the cell at its own level are present too ("interior").
//!
//! A sample at x is continuous everywhere and reproduces a linear field
//! exactly wherever some level has all eight cells around x:
//! - Level by level, finest first, the eight cells around x (the
//!   trilinear stencil) are read. Their trilinear weights summed over the
//!   interior ones give alpha in [0, 1], a continuous function that is
//!   above 0 only where the whole stencil is present (every cell within
//!   one cell of an interior cell is present). The level's trilinear
//!   value is taken with weight alpha times what finer levels left.
//!   Deep inside a level alpha is 1 and coarser levels are not read: the
//!   finest data wins. Across a level's edge it falls to 0 over one cell,
//!   so the coarser level's value takes over without a seam.
//! - What no complete stencil covers (levels sent without the coarse
//!   data under them, gaps between blocks) is filled by the basis method (tent weights of the present cells, levels blended by
//!   their weight sums): continuous, first order.
//! - Each level's stencil is clamped to the centres of the field's box
//!   at that level, so that at the box's faces every level reads as a
//!   grid clamped to its edge, and cells beyond the box count as present
//!   for the interior flag. Where no cell's tent reaches (a gap between
//!   blocks): NaN, like a mesh outside its cells.
//!
//! The basis method alone (what anari-visionaray samples) does not
//! reproduce a linear field across a level boundary: a smooth field
//! there is off by up to a quarter of a coarse cell times its gradient,
//! where trilinear interpolation inside a level is off by second-order
//! terms. docs/ray_casting.md has the measurement.
//!
//! Rays march an AMR field through a lattice over its box spaced by the
//! finest cell (at most MAX_LATTICE vertices per axis), as a mesh's:
//! the march, its step and the empty-space bricks are the structured
//! ones, and only the sample differs.

use glam::{IVec3, UVec3, Vec3};
use thiserror::Error;

/// Cells per brick edge, and cells per brick.
const AMR_BRICK: i32 = 8;
const AMR_BRICK_CELLS: usize = 512;
/// What a cell no block holds reads: a quiet NaN whose interior bit
/// (the lowest) is clear.
pub const AMR_ABSENT: u32 = 0x7fc0_0000;
/// An empty slot of the hash: its fourth word.
pub const AMR_EMPTY: u32 = u32::MAX;
/// Levels an AMR field may have: a hash entry keeps the level in 5 bits.
pub const MAX_AMR_LEVELS: usize = 31;
/// Bricks: a hash entry keeps the brick's index in 27 bits (the last
/// value marks an empty slot).
pub const MAX_AMR_BRICKS: u64 = (1 << 27) - 1;
pub const MAX_AMR_BLOCKS: u64 = 1 << 28;
pub const MAX_AMR_CELLS: u64 = 1 << 34;
/// Cell positions are single precision: a block's corners must lie
/// within 2^24 units, where every integer is exact.
const MAX_COORDINATE: f64 = (1u32 << 24) as f64;
/// Lattice vertices per axis at most.
const MAX_LATTICE: u32 = 1024;

/// One block: its cells' inclusive bounds in its level's index space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AmrBlock {
    pub lo: IVec3,
    pub hi: IVec3,
    pub level: u32,
}

impl AmrBlock {
    /// Cells per axis (0 where the bounds are empty).
    pub fn size(&self) -> [u64; 3] {
        let d = self.hi.as_i64vec3() - self.lo.as_i64vec3() + glam::I64Vec3::ONE;
        d.max(glam::I64Vec3::ZERO).to_array().map(|n| n as u64)
    }

    pub fn cells(&self) -> u64 {
        let [x, y, z] = self.size();
        x.saturating_mul(y).saturating_mul(z)
    }
}

/// An AMR field as hosts describe it: cell widths per level, blocks, and
/// every block's values, x fastest, one block after the other; placed
/// at world `origin + x * spacing` for AMR coordinates x.
#[derive(Clone, Debug, Default)]
pub struct AmrInput {
    pub widths: Vec<f32>,
    pub blocks: Vec<AmrBlock>,
    pub values: Vec<f32>,
    pub origin: Vec3,
    pub spacing: Vec3,
}

#[derive(Debug, Error, PartialEq)]
pub enum AmrError {
    #[error("an amr field needs at least one level's cell width")]
    NoLevels,
    #[error("{levels} levels; caveray takes up to {MAX_AMR_LEVELS}")]
    TooManyLevels { levels: usize },
    #[error("level {level}'s cell width is {width}; it must be finite and above 0")]
    BadWidth { level: usize, width: f32 },
    #[error("an amr field needs at least one block")]
    NoBlocks,
    #[error("{count} blocks; caveray takes up to {MAX_AMR_BLOCKS}")]
    TooManyBlocks { count: u64 },
    #[error("block {block} is at level {level}, and the field has {levels} levels")]
    LevelPastWidths {
        block: usize,
        level: i64,
        levels: usize,
    },
    #[error("block {block}'s bounds {lo} to {hi} hold no cell (an upper bound below the lower)")]
    EmptyBlock { block: usize, lo: IVec3, hi: IVec3 },
    #[error("block {block} reaches {reach} units from the origin; cell positions must stay within 2^24 units")]
    FarBlock { block: usize, reach: f64 },
    #[error("the blocks hold {count} cells; caveray takes up to {MAX_AMR_CELLS}")]
    TooManyCells { count: u64 },
    #[error("the blocks' cells need {needed} values; {got} given")]
    WrongLength { needed: u64, got: u64 },
    #[error("the blocks need {count} bricks of 8x8x8 cells; caveray takes up to {MAX_AMR_BRICKS}")]
    TooManyBricks { count: u64 },
    #[error("no cell of the field holds a finite value")]
    NoValues,
    #[error("grid spacing must be finite and above 0, got {0}")]
    BadSpacing(Vec3),
    #[error("grid origin must be finite, got {0}")]
    BadOrigin(Vec3),
    #[error("cannot allocate {bytes} bytes for the field's {what}")]
    OutOfMemory { bytes: u64, what: &'static str },
    #[error("no cell of the field reaches that box")]
    NoCells,
}

/// What `inspect` prints of one level.
#[derive(Clone, Debug, PartialEq)]
pub struct AmrLevel {
    pub width: f32,
    /// Cells holding a value.
    pub cells: u64,
    /// The inclusive bounds of those cells in the level's index space
    /// (empty where there are none: lo above hi).
    pub lo: IVec3,
    pub hi: IVec3,
}

#[derive(Clone, Debug, PartialEq)]
pub struct AmrVolume {
    widths: Vec<f32>,
    /// 1 / width per level: what a sample multiplies by.
    inverse_widths: Vec<f32>,
    /// Levels holding cells, finest first.
    order: Vec<u32>,
    /// AMR_BRICK_CELLS words per brick, x fastest.
    bricks: Vec<u32>,
    /// Each brick's level and brick coordinates.
    keys: Vec<(u32, IVec3)>,
    /// The hash: four words a slot, brick x, y, z and level << 27 | brick.
    table: Vec<u32>,
    /// The longest run of slots a lookup looks at.
    probes: u32,
    origin: Vec3,
    spacing: Vec3,
    /// The cells' box in AMR units.
    lo: Vec3,
    hi: Vec3,
    /// Per level, the range its stencils' lower corners are clamped to
    /// (its cell-centre coordinates x / w - 1/2): the first to the last
    /// centre of the whole field's box at that level, so that at the
    /// box's faces every level reads as a grid clamped to its edge.
    clamps: Vec<(Vec3, Vec3)>,
    lattice_dims: UVec3,
    lattice_step: Vec3,
    value_range: (f32, f32),
    levels: Vec<AmrLevel>,
    blocks: usize,
    /// Values read as no value (NaN or infinite).
    dropped: u64,
}

fn reserve<T>(n: u64, what: &'static str) -> Result<Vec<T>, AmrError> {
    let oom = || AmrError::OutOfMemory {
        bytes: n.saturating_mul(std::mem::size_of::<T>() as u64),
        what,
    };
    let n = usize::try_from(n).map_err(|_| oom())?;
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| oom())?;
    Ok(v)
}

/// The hash's slot for a brick: the same mixing as shaders/amr.wgsl.
fn amr_slot(level: u32, b: IVec3, mask: u32) -> u32 {
    let h = (b.x as u32).wrapping_mul(0x9e37_79b1)
        ^ (b.y as u32).wrapping_mul(0x85eb_ca77)
        ^ (b.z as u32).wrapping_mul(0xc2b2_ae3d)
        ^ level.wrapping_mul(0x27d4_eb2f);
    (h ^ (h >> 15)) & mask
}

fn brick_of(cell: IVec3) -> IVec3 {
    cell >> 3
}

fn local_of(cell: IVec3) -> usize {
    let l = cell & IVec3::splat(AMR_BRICK - 1);
    (l.x + AMR_BRICK * (l.y + AMR_BRICK * l.z)) as usize
}

fn present(word: u32) -> bool {
    word != AMR_ABSENT
}

/// A present cell's value, without its interior flag.
fn value(word: u32) -> f32 {
    f32::from_bits(word & !1)
}

/// Checks counts and bounds before anything is allocated.
fn check(input: &AmrInput) -> Result<u64, AmrError> {
    let levels = input.widths.len();
    if levels == 0 {
        return Err(AmrError::NoLevels);
    }
    if levels > MAX_AMR_LEVELS {
        return Err(AmrError::TooManyLevels { levels });
    }
    for (level, &width) in input.widths.iter().enumerate() {
        if !(width.is_finite() && width > 0.0) {
            return Err(AmrError::BadWidth { level, width });
        }
    }
    if !input.origin.is_finite() {
        return Err(AmrError::BadOrigin(input.origin));
    }
    if !(input.spacing.is_finite() && input.spacing.cmpgt(Vec3::ZERO).all()) {
        return Err(AmrError::BadSpacing(input.spacing));
    }
    if input.blocks.is_empty() {
        return Err(AmrError::NoBlocks);
    }
    let count = input.blocks.len() as u64;
    if count > MAX_AMR_BLOCKS {
        return Err(AmrError::TooManyBlocks { count });
    }
    let mut cells = 0u64;
    for (i, b) in input.blocks.iter().enumerate() {
        if b.level as usize >= levels {
            return Err(AmrError::LevelPastWidths {
                block: i,
                level: i64::from(b.level),
                levels,
            });
        }
        if b.hi.cmplt(b.lo).any() {
            return Err(AmrError::EmptyBlock {
                block: i,
                lo: b.lo,
                hi: b.hi,
            });
        }
        let w = f64::from(input.widths[b.level as usize]);
        let reach = (b.lo.as_dvec3() * w)
            .abs()
            .max((b.hi.as_dvec3() + glam::DVec3::ONE) * w)
            .abs()
            .max_element();
        if reach > MAX_COORDINATE {
            return Err(AmrError::FarBlock { block: i, reach });
        }
        cells = cells.saturating_add(b.cells());
    }
    if cells > MAX_AMR_CELLS {
        return Err(AmrError::TooManyCells { count: cells });
    }
    if input.values.len() as u64 != cells {
        return Err(AmrError::WrongLength {
            needed: cells,
            got: input.values.len() as u64,
        });
    }
    Ok(cells)
}

/// The hash over `keys`, and its longest probe run.
fn hash(keys: &[(u32, IVec3)]) -> Result<(Vec<u32>, u32), AmrError> {
    let slots = (2 * keys.len() as u64).next_power_of_two().max(16);
    let mut table = reserve::<u32>(4 * slots, "brick hash")?;
    table.resize(4 * slots as usize, AMR_EMPTY);
    let mask = (slots - 1) as u32;
    let mut probes = 1;
    for (k, &(level, b)) in keys.iter().enumerate() {
        let mut s = amr_slot(level, b, mask);
        let mut run = 1;
        while table[4 * s as usize + 3] != AMR_EMPTY {
            s = (s + 1) & mask;
            run += 1;
        }
        let at = 4 * s as usize;
        table[at..at + 4].copy_from_slice(&[
            b.x as u32,
            b.y as u32,
            b.z as u32,
            level << 27 | k as u32,
        ]);
        probes = probes.max(run);
    }
    Ok((table, probes))
}

fn find(table: &[u32], probes: u32, level: u32, b: IVec3) -> Option<usize> {
    let mask = (table.len() / 4 - 1) as u32;
    let mut s = amr_slot(level, b, mask);
    for _ in 0..probes {
        let e = &table[4 * s as usize..4 * s as usize + 4];
        if e[3] == AMR_EMPTY {
            return None;
        }
        if e[3] >> 27 == level && [e[0], e[1], e[2]] == [b.x as u32, b.y as u32, b.z as u32] {
            return Some((e[3] & ((1 << 27) - 1)) as usize);
        }
        s = (s + 1) & mask;
    }
    None
}

/// Per level of width `w`, the cells of the box `lo..hi` (AMR units):
/// those a clamped stencil reads.
fn level_cells(widths: &[f32], (lo, hi): (Vec3, Vec3)) -> Vec<(IVec3, IVec3)> {
    widths
        .iter()
        .map(|&w| {
            let c0 = (lo / w).floor().as_ivec3();
            let c1 = ((hi / w).ceil().as_ivec3() - IVec3::ONE).max(c0);
            (c0, c1)
        })
        .collect()
}

/// Marks every present cell whose 26 neighbours at its level are present
/// too, or lie beyond the field's box (where clamped stencils never
/// reach): a 3x3x3 erosion of presence, separable, over each brick padded
/// by one cell from its neighbours.
fn mark_interior(
    bricks: &mut [u32],
    keys: &[(u32, IVec3)],
    (table, probes): (&[u32], u32),
    cells: &[(IVec3, IVec3)],
) {
    const P: usize = AMR_BRICK as usize + 2;
    let idx = |x: usize, y: usize, z: usize| x + P * (y + P * z);
    let mut a = [false; P * P * P];
    let mut b = [false; P * P * P];
    for (k, &(level, key)) in keys.iter().enumerate() {
        let mut near = [None; 27];
        for (n, slot) in near.iter_mut().enumerate() {
            let d = IVec3::new(n as i32 % 3, n as i32 / 3 % 3, n as i32 / 9) - IVec3::ONE;
            *slot = if d == IVec3::ZERO {
                Some(k)
            } else {
                find(table, probes, level, key + d)
            };
        }
        for z in 0..P {
            for y in 0..P {
                for x in 0..P {
                    let c = IVec3::new(x as i32, y as i32, z as i32) - IVec3::ONE;
                    let d = (c + IVec3::splat(AMR_BRICK)) / AMR_BRICK;
                    let n = (d.x + 3 * d.y + 9 * d.z) as usize;
                    let (c0, c1) = cells[level as usize];
                    let cell = key * AMR_BRICK + c;
                    let beyond = cell.cmplt(c0).any() || cell.cmpgt(c1).any();
                    a[idx(x, y, z)] = beyond
                        || near[n]
                            .is_some_and(|m| present(bricks[m * AMR_BRICK_CELLS + local_of(c)]));
                }
            }
        }
        erode(&a, &mut b, 0);
        erode(&b, &mut a, 1);
        erode(&a, &mut b, 2);
        let base = k * AMR_BRICK_CELLS;
        for z in 0..AMR_BRICK as usize {
            for y in 0..AMR_BRICK as usize {
                for x in 0..AMR_BRICK as usize {
                    let i = base + x + 8 * (y + 8 * z);
                    // The flag is the lowest bit, which presence does not
                    // read (an absent word's is clear, a present value's
                    // was cleared on input): marked in place.
                    if present(bricks[i]) {
                        bricks[i] = (bricks[i] & !1) | u32::from(b[idx(x + 1, y + 1, z + 1)]);
                    }
                }
            }
        }
    }
}

/// `to` = `from` where both neighbours along `axis` are set too (false
/// at the padding's edge).
fn erode(from: &[bool], to: &mut [bool], axis: usize) {
    const P: usize = AMR_BRICK as usize + 2;
    let stride = [1, P, P * P][axis];
    for z in 0..P {
        for y in 0..P {
            for x in 0..P {
                let i = x + P * (y + P * z);
                let c = [x, y, z][axis];
                to[i] = from[i] && c > 0 && c + 1 < P && from[i - stride] && from[i + stride];
            }
        }
    }
}

/// The eight cells around a point at one level (x fastest), and its
/// place among them.
struct Stencil {
    words: [u32; 8],
    f: Vec3,
}

impl Stencil {
    /// Trilinear interpolation of the eight values.
    fn trilinear(&self) -> f32 {
        let v = self.words.map(value);
        let f = self.f;
        let x00 = v[0] + (v[1] - v[0]) * f.x;
        let x10 = v[2] + (v[3] - v[2]) * f.x;
        let x01 = v[4] + (v[5] - v[4]) * f.x;
        let x11 = v[6] + (v[7] - v[6]) * f.x;
        let y0 = x00 + (x10 - x00) * f.y;
        let y1 = x01 + (x11 - x01) * f.y;
        y0 + (y1 - y0) * f.z
    }

    /// The trilinear weights summed over the interior cells (alpha) and
    /// over the present ones, and the present ones' weighted values.
    fn sums(&self) -> (f32, f32, f32) {
        let (mut alpha, mut weights, mut sum) = (0.0, 0.0, 0.0);
        for (n, &w) in self.words.iter().enumerate() {
            if !present(w) {
                continue;
            }
            let wx = if n & 1 == 1 { self.f.x } else { 1.0 - self.f.x };
            let wy = if n & 2 == 2 { self.f.y } else { 1.0 - self.f.y };
            let wz = if n & 4 == 4 { self.f.z } else { 1.0 - self.f.z };
            let weight = wx * wy * wz;
            weights += weight;
            sum += weight * value(w);
            if w & 1 == 1 {
                alpha += weight;
            }
        }
        (alpha, weights, sum)
    }
}

impl AmrVolume {
    pub fn new(input: AmrInput) -> Result<Self, AmrError> {
        check(&input)?;
        // Every brick each block touches, deduplicated through the hash.
        let mut touched = 0u64;
        for b in &input.blocks {
            let n = brick_of(b.hi) - brick_of(b.lo) + IVec3::ONE;
            touched = touched.saturating_add(n.as_u64vec3().element_product());
        }
        if touched > MAX_AMR_BRICKS.saturating_mul(8) {
            return Err(AmrError::TooManyBricks { count: touched });
        }
        let mut keys: Vec<(u32, IVec3)> = reserve(touched, "bricks")?;
        {
            let slots = (2 * touched).next_power_of_two().max(16);
            let mut seen = reserve::<u32>(4 * slots, "brick hash")?;
            seen.resize(4 * slots as usize, AMR_EMPTY);
            let mask = (slots - 1) as u32;
            for blk in &input.blocks {
                let (b0, b1) = (brick_of(blk.lo), brick_of(blk.hi));
                for z in b0.z..=b1.z {
                    for y in b0.y..=b1.y {
                        for x in b0.x..=b1.x {
                            let b = IVec3::new(x, y, z);
                            let mut s = amr_slot(blk.level, b, mask);
                            loop {
                                let e = &mut seen[4 * s as usize..4 * s as usize + 4];
                                if e[3] == AMR_EMPTY {
                                    e.copy_from_slice(&[
                                        b.x as u32, b.y as u32, b.z as u32, blk.level,
                                    ]);
                                    keys.push((blk.level, b));
                                    break;
                                }
                                if e[3] == blk.level
                                    && e[..3] == [b.x as u32, b.y as u32, b.z as u32]
                                {
                                    break;
                                }
                                s = (s + 1) & mask;
                            }
                        }
                    }
                }
            }
        }
        if keys.len() as u64 > MAX_AMR_BRICKS {
            return Err(AmrError::TooManyBricks {
                count: keys.len() as u64,
            });
        }
        keys.shrink_to_fit();
        let (table, probes) = hash(&keys)?;
        let mut bricks = reserve::<u32>(keys.len() as u64 * AMR_BRICK_CELLS as u64, "bricks")?;
        bricks.resize(keys.len() * AMR_BRICK_CELLS, AMR_ABSENT);
        let mut dropped = 0;
        let mut at = 0;
        for blk in &input.blocks {
            let mut last = (IVec3::splat(i32::MIN), 0);
            for z in blk.lo.z..=blk.hi.z {
                for y in blk.lo.y..=blk.hi.y {
                    for x in blk.lo.x..=blk.hi.x {
                        let c = IVec3::new(x, y, z);
                        let b = brick_of(c);
                        if b != last.0 {
                            let k = find(&table, probes, blk.level, b)
                                .expect("every block's bricks are in the hash");
                            last = (b, k);
                        }
                        let v = input.values[at];
                        at += 1;
                        bricks[last.1 * AMR_BRICK_CELLS + local_of(c)] = if v.is_finite() {
                            // The lowest bit is the interior flag.
                            v.to_bits() & !1
                        } else {
                            dropped += 1;
                            AMR_ABSENT
                        };
                    }
                }
            }
        }
        // The blocks' box, which clamps every level's stencils.
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for b in &input.blocks {
            let w = input.widths[b.level as usize];
            lo = lo.min(b.lo.as_vec3() * w);
            hi = hi.max((b.hi + IVec3::ONE).as_vec3() * w);
        }
        let cells = level_cells(&input.widths, (lo, hi));
        mark_interior(&mut bricks, &keys, (&table, probes), &cells);
        let clamps = cells
            .iter()
            .map(|&(c0, c1)| (c0.as_vec3(), c1.as_vec3()))
            .collect();
        let mut volume = Self::assemble(
            input.widths,
            bricks,
            keys,
            (table, probes),
            (input.origin, input.spacing),
            clamps,
        )?;
        volume.blocks = input.blocks.len();
        volume.dropped = dropped;
        Ok(volume)
    }

    /// The volume of these bricks (their interior flags as they are).
    fn assemble(
        widths: Vec<f32>,
        bricks: Vec<u32>,
        keys: Vec<(u32, IVec3)>,
        (table, probes): (Vec<u32>, u32),
        (origin, spacing): (Vec3, Vec3),
        clamps: Vec<(Vec3, Vec3)>,
    ) -> Result<Self, AmrError> {
        let mut levels: Vec<AmrLevel> = widths
            .iter()
            .map(|&width| AmrLevel {
                width,
                cells: 0,
                lo: IVec3::MAX,
                hi: IVec3::MIN,
            })
            .collect();
        let (mut vlo, mut vhi) = (f32::INFINITY, f32::NEG_INFINITY);
        for (k, &(level, b)) in keys.iter().enumerate() {
            let l = &mut levels[level as usize];
            let words = &bricks[k * AMR_BRICK_CELLS..(k + 1) * AMR_BRICK_CELLS];
            for (i, &w) in words.iter().enumerate() {
                if !present(w) {
                    continue;
                }
                let i = i as i32;
                let c = b * AMR_BRICK + IVec3::new(i % 8, i / 8 % 8, i / 64);
                l.cells += 1;
                l.lo = l.lo.min(c);
                l.hi = l.hi.max(c);
                vlo = vlo.min(value(w));
                vhi = vhi.max(value(w));
            }
        }
        if vlo > vhi {
            return Err(AmrError::NoValues);
        }
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for l in levels.iter().filter(|l| l.cells > 0) {
            lo = lo.min(l.lo.as_vec3() * l.width);
            hi = hi.max((l.hi + IVec3::ONE).as_vec3() * l.width);
        }
        let mut order: Vec<u32> = (0..levels.len() as u32)
            .filter(|&l| levels[l as usize].cells > 0)
            .collect();
        order.sort_by(|&a, &b| widths[a as usize].total_cmp(&widths[b as usize]));
        let finest = widths[order[0] as usize];
        let extent = hi - lo;
        let mut lattice_dims = UVec3::ONE;
        let mut lattice_step = Vec3::ONE;
        for k in 0..3 {
            // A hair under the quotient, so that a box of whole cells gets
            // exactly one vertex per cell edge.
            let cells = (extent[k] / finest * (1.0 - 1e-6))
                .ceil()
                .clamp(1.0, (MAX_LATTICE - 1) as f32);
            lattice_dims[k] = cells as u32 + 1;
            lattice_step[k] = extent[k] / cells;
        }
        Ok(Self {
            inverse_widths: widths.iter().map(|w| w.recip()).collect(),
            widths,
            order,
            bricks,
            keys,
            table,
            probes,
            origin,
            spacing,
            lo,
            hi,
            clamps,
            lattice_dims,
            lattice_step,
            value_range: (vlo, vhi),
            levels,
            blocks: 0,
            dropped: 0,
        })
    }

    /// The cells of these bricks whose tents reach the box `lo..=hi`
    /// (AMR units): a sample in the box reads the same as in `self`.
    pub fn cells_within(&self, lo: Vec3, hi: Vec3) -> Result<Self, AmrError> {
        let mut keys = Vec::new();
        let mut bricks = Vec::new();
        for (k, &(level, b)) in self.keys.iter().enumerate() {
            let (a, z) = self.brick_reach(level, b);
            if a.cmpgt(hi).any() || z.cmplt(lo).any() {
                continue;
            }
            keys.push((level, b));
            bricks.extend_from_slice(&self.bricks[k * AMR_BRICK_CELLS..(k + 1) * AMR_BRICK_CELLS]);
        }
        if keys.is_empty() {
            return Err(AmrError::NoCells);
        }
        let table = hash(&keys)?;
        let mut v = Self::assemble(
            self.widths.clone(),
            bricks,
            keys,
            table,
            (self.origin, self.spacing),
            self.clamps.clone(),
        )?;
        v.blocks = self.blocks;
        Ok(v)
    }

    /// The box (AMR units) a brick's cells' tents cover: one cell beyond
    /// their centres.
    fn brick_reach(&self, level: u32, b: IVec3) -> (Vec3, Vec3) {
        let w = self.widths[level as usize];
        let c0 = (b * AMR_BRICK).as_vec3();
        ((c0 - 0.5) * w, (c0 + AMR_BRICK as f32 + 0.5) * w)
    }

    /// Each present cell's tent box (AMR units: one cell beyond its
    /// centre, where a sample can read it) and its value, twice.
    pub fn cell_ranges(&self) -> impl Iterator<Item = ((Vec3, Vec3), (f32, f32))> + '_ {
        self.keys
            .iter()
            .enumerate()
            .flat_map(move |(k, &(level, b))| {
                let w = self.widths[level as usize];
                let words = &self.bricks[k * AMR_BRICK_CELLS..(k + 1) * AMR_BRICK_CELLS];
                words.iter().enumerate().filter_map(move |(i, &word)| {
                    if !present(word) {
                        return None;
                    }
                    let i = i as i32;
                    let c = b * AMR_BRICK + IVec3::new(i % 8, i / 8 % 8, i / 64);
                    let centre = (c.as_vec3() + 0.5) * w;
                    let v = value(word);
                    Some(((centre - w, centre + w), (v, v)))
                })
            })
    }

    fn stencil(&self, level: u32, x: Vec3) -> Stencil {
        let (c0, c1) = self.clamps[level as usize];
        let u = (x * self.inverse_widths[level as usize] - Vec3::splat(0.5)).clamp(c0, c1);
        // floor without libm's call: truncate, then one down where that
        // rounded up (below 0).
        let t = u.as_ivec3();
        let i0 = IVec3::select(u.cmplt(t.as_vec3()), t - IVec3::ONE, t);
        let f = u - i0.as_vec3();
        let mut words = [AMR_ABSENT; 8];
        let (b0, b1) = (brick_of(i0), brick_of(i0 + IVec3::ONE));
        if b0 == b1 {
            if let Some(k) = find(&self.table, self.probes, level, b0) {
                let base = k * AMR_BRICK_CELLS + local_of(i0);
                let cells = &self.bricks[base..=base + 73];
                for (n, w) in words.iter_mut().enumerate() {
                    *w = cells[(n & 1) + 8 * (n >> 1 & 1) + 64 * (n >> 2)];
                }
            }
        } else {
            let mut last = (IVec3::splat(i32::MIN), None);
            for (n, w) in words.iter_mut().enumerate() {
                let c = i0 + IVec3::new((n & 1) as i32, (n >> 1 & 1) as i32, (n >> 2) as i32);
                let b = brick_of(c);
                if b != last.0 {
                    last = (b, find(&self.table, self.probes, level, b));
                }
                if let Some(k) = last.1 {
                    *w = self.bricks[k * AMR_BRICK_CELLS + local_of(c)];
                }
            }
        }
        Stencil { words, f }
    }

    /// The field at `x` (AMR units); NaN where no cell's tent reaches.
    pub fn sample(&self, x: Vec3) -> f32 {
        let mut remaining = 1.0;
        let mut acc = 0.0;
        for &level in &self.order {
            let s = self.stencil(level, x);
            // Eight interior cells (the interior bit set in all, which an
            // absent cell's word lacks): alpha is 1, the level's trilinear
            // value all that is left to take.
            if s.words.iter().fold(1, |a, &w| a & w) == 1 {
                return acc + remaining * s.trilinear();
            }
            let (alpha, _, sum) = s.sums();
            if alpha > 0.0 {
                // Every cell is present: `sum` is the trilinear value.
                acc += remaining * alpha * sum;
                remaining *= 1.0 - alpha;
                if remaining <= 0.0 {
                    return acc;
                }
            }
        }
        // What no whole stencil covered: the basis method, each level's
        // tents blended by their weight sums.
        let (mut left, mut filled) = (1.0, 0.0);
        for &level in &self.order {
            let (_, weights, sum) = self.stencil(level, x).sums();
            filled += left * sum;
            left *= 1.0 - weights;
        }
        if left >= 1.0 {
            return f32::NAN;
        }
        acc + remaining * filled / (1.0 - left)
    }

    /// The field at world point `p`.
    pub fn sample_world(&self, p: Vec3) -> f32 {
        self.sample((p - self.origin) / self.spacing)
    }

    /// The world box of the cells.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (
            self.origin + self.lo * self.spacing,
            self.origin + self.hi * self.spacing,
        )
    }

    /// The cells' box in AMR units.
    pub fn amr_bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.hi)
    }

    /// Lattice vertices per axis and their spacing (world units).
    pub fn lattice(&self) -> (UVec3, Vec3) {
        (self.lattice_dims, self.lattice_step * self.spacing)
    }

    /// The lattice's spacing in AMR units.
    pub fn lattice_step(&self) -> Vec3 {
        self.lattice_step
    }

    /// The finest cell's edges (world units): what sets the step.
    pub fn finest_cell(&self) -> Vec3 {
        self.widths[self.order[0] as usize] * self.spacing
    }

    pub fn value_range(&self) -> (f32, f32) {
        self.value_range
    }

    /// Per level as given: its width, cells and their bounds.
    pub fn levels(&self) -> &[AmrLevel] {
        &self.levels
    }

    /// Blocks the host sent.
    pub fn block_count(&self) -> usize {
        self.blocks
    }

    /// Values read as no value (NaN or infinite).
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Levels holding cells, finest first.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    pub fn widths(&self) -> &[f32] {
        &self.widths
    }

    pub fn brick_words(&self) -> &[u32] {
        &self.bricks
    }

    pub fn table(&self) -> &[u32] {
        &self.table
    }

    pub fn probes(&self) -> u32 {
        self.probes
    }

    /// Per level, the range its stencils' lower corners are clamped to.
    pub fn clamps(&self) -> &[(Vec3, Vec3)] {
        &self.clamps
    }

    /// Bytes held: the bricks and the hash.
    pub fn bytes(&self) -> u64 {
        4 * (self.bricks.len() + self.table.len()) as u64 + 16 * self.keys.len() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A coarse level of width 2 over [0, 32)^3 and a fine level of width
    /// 1 over [8, 24)^3 (parents sent), both sampling `f` at their centres.
    fn two_levels(f: impl Fn(Vec3) -> f32) -> AmrVolume {
        let mut values = Vec::new();
        let mut blocks = Vec::new();
        for (level, w, lo, hi) in [(1u32, 2.0f32, 0, 15), (0, 1.0, 8, 23)] {
            blocks.push(AmrBlock {
                lo: IVec3::splat(lo),
                hi: IVec3::splat(hi),
                level,
            });
            for z in lo..=hi {
                for y in lo..=hi {
                    for x in lo..=hi {
                        let c = (IVec3::new(x, y, z).as_vec3() + 0.5) * w;
                        values.push(f(c));
                    }
                }
            }
        }
        AmrVolume::new(AmrInput {
            widths: vec![1.0, 2.0],
            blocks,
            values,
            origin: Vec3::ZERO,
            spacing: Vec3::ONE,
        })
        .unwrap()
    }

    #[test]
    fn a_linear_field_is_exact_wherever_a_level_has_a_whole_stencil() {
        let f = |p: Vec3| 0.3 * p.x - 0.2 * p.y + 0.7 * p.z + 1.0;
        let amr = two_levels(f);
        // Within the coarse cells' centres (1 to 31), across the fine
        // level's edges at 8 and 24.
        let mut worst: f32 = 0.0;
        for i in 0..400 {
            let t = i as f32 / 399.0;
            let p = Vec3::new(1.0 + 30.0 * t, 5.0 + 17.3 * t, 16.2 - 9.0 * t);
            worst = worst.max((amr.sample(p) - f(p)).abs());
        }
        assert!(worst < 1e-4, "off by {worst}");
    }

    #[test]
    fn the_sample_is_continuous_across_the_level_boundary() {
        let f = |p: Vec3| (p.x * 0.4).sin() * (p.y * 0.3).cos() + 0.1 * p.z;
        let amr = two_levels(f);
        let h = 1e-3;
        let mut worst: f32 = 0.0;
        for i in 0..2000 {
            let x = 4.0 + 8.0 * i as f32 / 1999.0;
            let p = Vec3::new(x, 16.3, 15.7);
            let jump = (amr.sample(p + Vec3::X * h) - amr.sample(p)).abs();
            worst = worst.max(jump);
        }
        // The field's own change over h is at most 0.4 h.
        assert!(worst < 0.4 * h * 4.0, "jumps by {worst}");
    }

    #[test]
    fn the_error_along_the_level_boundary_is_no_larger_than_inside_either_level() {
        let f = |p: Vec3| (0.35 * p.x).sin() * (0.3 * p.y).cos() + (0.25 * p.z).sin();
        let amr = two_levels(f);
        let mut seed = 12345u32;
        let mut next = move || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32
        };
        let mut worst = |lo: Vec3, hi: Vec3| -> f32 {
            (0..4000)
                .map(|_| {
                    let p = lo + (hi - lo) * Vec3::new(next(), next(), next());
                    (amr.sample(p) - f(p)).abs()
                })
                .fold(0.0, f32::max)
        };
        // The fine level spans [8, 24)^3, the coarse [0, 32)^3; the
        // blend runs from 1.5 fine cells inside the fine box out to the
        // coarse stencils reaching in.
        let fine = worst(Vec3::splat(10.0), Vec3::splat(22.0));
        let coarse = worst(Vec3::new(1.0, 1.0, 1.0), Vec3::new(6.0, 31.0, 31.0));
        let boundary = worst(Vec3::new(6.0, 10.0, 10.0), Vec3::new(10.0, 22.0, 22.0)).max(worst(
            Vec3::new(10.0, 22.0, 10.0),
            Vec3::new(22.0, 26.0, 22.0),
        ));
        assert!(
            boundary <= fine.max(coarse),
            "boundary {boundary}, fine {fine}, coarse {coarse}"
        );
        assert!(fine < coarse, "fine {fine}, coarse {coarse}");
    }

    #[test]
    fn the_finest_level_wins_inside_it() {
        // Coarse and fine values disagree: inside the fine level (more
        // than 1.5 fine cells from its edge) only the fine one shows.
        let amr = two_levels(|p| if p.x > 0.0 { 1.0 } else { 0.0 });
        let mut values = Vec::new();
        let mut blocks = Vec::new();
        for (level, lo, hi, v) in [(1u32, 0, 15, 5.0f32), (0, 8, 23, 9.0)] {
            blocks.push(AmrBlock {
                lo: IVec3::splat(lo),
                hi: IVec3::splat(hi),
                level,
            });
            values.extend(std::iter::repeat_n(v, ((hi - lo + 1) as usize).pow(3)));
        }
        let mixed = AmrVolume::new(AmrInput {
            widths: vec![1.0, 2.0],
            blocks,
            values,
            origin: Vec3::ZERO,
            spacing: Vec3::ONE,
        })
        .unwrap();
        assert_eq!(mixed.sample(Vec3::splat(16.0)), 9.0);
        assert_eq!(mixed.sample(Vec3::new(10.0, 12.0, 22.0)), 9.0);
        assert_eq!(mixed.sample(Vec3::splat(4.0)), 5.0);
        let between = mixed.sample(Vec3::new(9.0, 16.0, 16.0));
        assert!(between > 5.0 && between < 9.0, "{between}");
        assert_eq!(amr.sample(Vec3::splat(16.0)), 1.0);
        // Beyond the box, as at its face.
        assert_eq!(amr.sample(Vec3::splat(40.0)), 1.0);
        assert_eq!(amr.value_range(), (1.0, 1.0));
    }

    #[test]
    fn bad_tables_are_refused_by_name() {
        let block = AmrBlock {
            lo: IVec3::ZERO,
            hi: IVec3::ONE,
            level: 0,
        };
        let input = |widths: Vec<f32>, blocks: Vec<AmrBlock>, n: usize| AmrInput {
            widths,
            blocks,
            values: vec![1.0; n],
            origin: Vec3::ZERO,
            spacing: Vec3::ONE,
        };
        assert_eq!(
            AmrVolume::new(input(vec![], vec![block], 8)),
            Err(AmrError::NoLevels)
        );
        assert_eq!(
            AmrVolume::new(input(vec![0.0], vec![block], 8)),
            Err(AmrError::BadWidth {
                level: 0,
                width: 0.0
            })
        );
        assert_eq!(
            AmrVolume::new(input(vec![1.0], vec![AmrBlock { level: 2, ..block }], 8)),
            Err(AmrError::LevelPastWidths {
                block: 0,
                level: 2,
                levels: 1
            })
        );
        let empty = AmrBlock {
            lo: IVec3::ONE,
            hi: IVec3::ZERO,
            level: 0,
        };
        assert!(matches!(
            AmrVolume::new(input(vec![1.0], vec![empty], 8)),
            Err(AmrError::EmptyBlock { block: 0, .. })
        ));
        assert_eq!(
            AmrVolume::new(input(vec![1.0], vec![block], 7)),
            Err(AmrError::WrongLength { needed: 8, got: 7 })
        );
        let far = AmrBlock {
            lo: IVec3::splat(i32::MAX - 1),
            hi: IVec3::splat(i32::MAX - 1),
            level: 0,
        };
        assert!(matches!(
            AmrVolume::new(input(vec![1.0], vec![far], 1)),
            Err(AmrError::FarBlock { block: 0, .. })
        ));
        assert_eq!(
            AmrVolume::new(AmrInput {
                values: vec![f32::NAN; 8],
                ..input(vec![1.0], vec![block], 8)
            }),
            Err(AmrError::NoValues)
        );
    }

    #[test]
    fn a_cropped_field_samples_as_the_whole_within_its_box() {
        let f = |p: Vec3| (p.x * 0.3).sin() + p.y * 0.05 - (p.z * 0.2).cos();
        let amr = two_levels(f);
        let (lo, hi) = (Vec3::new(4.0, 6.0, 5.0), Vec3::new(14.0, 20.0, 30.0));
        let part = amr.cells_within(lo, hi).unwrap();
        assert!(part.bytes() < amr.bytes());
        for i in 0..300 {
            let t = i as f32 / 299.0;
            let p = lo + (hi - lo) * Vec3::new(t, (t * 7.0).fract(), (t * 13.0).fract());
            assert_eq!(part.sample(p).to_bits(), amr.sample(p).to_bits(), "at {p}");
        }
    }
}
