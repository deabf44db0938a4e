//! NanoVDB grids on the GPU: each laid out as u32 words in the same
//! storage buffer as the meshes (`meshes`), which shaders/nanovdb.wgsl
//! reads where a volume slot's sampling is FILTER_VDB. The grid's own
//! words go as they are; only the root's tiles are restated, because
//! their 64-bit keys are awkward in WGSL.
//!
//! One grid, from its first word a, offsets relative to a:
//! - a + 0: the value code (VdbValues::code: 0 Float, 1 Half, else the
//!   log2 of a quantized code's bits); a + 1: 1 for nearest filtering;
//! - a + 2: root tiles; a + 3: where they begin; a + 4: where the grid's
//!   words begin; a + 5: the background (f32);
//! - a + 6..9: the lattice's first voxel in index space (i32);
//! - the tiles, five words each: their first voxel (3 i32), their upper
//!   node's first word relative to the grid's (or VDB_NONE), their value;
//! - the grid's words.

use crate::scene::{Filter, NanoVdbGrid};

/// Words before the tiles, and words a tile.
const HEADER: usize = 9;
const TILE: usize = 5;
/// A tile without an upper node.
const NONE: u32 = u32::MAX;

/// Words `grid` takes in the buffer.
pub(super) fn word_count(grid: &NanoVdbGrid) -> u64 {
    (HEADER + TILE * grid.tiles().len() + grid.words().len()) as u64
}

/// Appends `grid`'s words to `words`.
pub(super) fn pack(grid: &NanoVdbGrid, words: &mut Vec<u32>) {
    let tiles = grid.tiles();
    words.extend([
        grid.values().code(),
        u32::from(grid.filter() == Filter::Nearest),
        tiles.len() as u32,
        HEADER as u32,
        (HEADER + TILE * tiles.len()) as u32,
        grid.background().to_bits(),
    ]);
    words.extend(grid.window_origin().to_array().map(|i| i as u32));
    for t in tiles {
        words.extend(t.origin.to_array().map(|i| i as u32));
        words.extend([t.child.map_or(NONE, |c| c / 4), t.value.to_bits()]);
    }
    words.extend_from_slice(grid.words());
}
