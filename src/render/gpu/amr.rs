//! AMR fields on the GPU: each laid out as u32 words in the same storage
//! buffer as the meshes (`meshes`), which shaders/amr.wgsl reads where a
//! volume slot's sampling is FILTER_AMR.
//!
//! One field, from its first word a, offsets relative to a:
//! - a + 0: levels holding cells; a + 1: the hash's slot mask; a + 2: the
//!   longest probe run; a + 3: where the hash begins; a + 4: where the
//!   bricks begin;
//! - a + 5..8: the lattice's origin, a + 8..11: its step (f32, AMR units);
//! - a + 11 on, eight words a level, finest first: its number, 1 / its
//!   cell width (f32) and the range its stencils are clamped to (6 f32);
//! - the hash, four words a slot (scene::amr);
//! - the bricks, AMR_BRICK_CELLS words each.

use crate::scene::AmrVolume;

/// Words before a field's levels.
const HEADER: usize = 11;

/// Words `amr` takes in the buffer.
pub(super) fn word_count(amr: &AmrVolume) -> u64 {
    (HEADER + 8 * amr.order().len() + amr.table().len() + amr.brick_words().len()) as u64
}

/// Appends `amr`'s words to `words`.
pub(super) fn pack(amr: &AmrVolume, words: &mut Vec<u32>) {
    let levels = 8 * amr.order().len();
    let table = amr.table().len();
    words.extend([
        amr.order().len() as u32,
        (table / 4 - 1) as u32,
        amr.probes(),
        (HEADER + levels) as u32,
        (HEADER + levels + table) as u32,
    ]);
    words.extend(amr.amr_bounds().0.to_array().map(f32::to_bits));
    words.extend(amr.lattice_step().to_array().map(f32::to_bits));
    for &level in amr.order() {
        let (c0, c1) = amr.clamps()[level as usize];
        words.extend([level, amr.widths()[level as usize].recip().to_bits()]);
        words.extend(c0.to_array().map(f32::to_bits));
        words.extend(c1.to_array().map(f32::to_bits));
    }
    words.extend_from_slice(amr.table());
    words.extend_from_slice(amr.brick_words());
}
