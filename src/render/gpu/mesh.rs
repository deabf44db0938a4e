//! Unstructured fields on the GPU: each mesh laid out as u32 words in one
//! storage buffer (`meshes`), which shaders/volume.wgsl reads where a
//! volume slot's sampling is FILTER_CELLS.
//!
//! One mesh, from its first word m, offsets relative to m:
//! - m + 0..5: where its nodes, cells, index, positions and values begin;
//! - m + 5: 1 where values are per vertex, 0 per cell;
//! - m + 6..9: its lattice's origin, m + 9..12: the lattice spacing (f32);
//! - nodes, 8 words each: box min (3 f32), first, box max (3 f32), count
//!   (scene::MeshNode);
//! - cells in BVH order, one word each: first index << 2 | kind code;
//! - the index; positions, 3 f32 each; values, one f32 each.

use super::context::Context;
use crate::render::RenderError;
use crate::scene::UnstructuredVolume;

/// Words before a mesh's nodes.
const HEADER: usize = 12;

/// Words `mesh` takes in the buffer.
pub(super) fn word_count(mesh: &UnstructuredVolume) -> u64 {
    (HEADER
        + 8 * mesh.nodes().len()
        + mesh.cell_words().len()
        + mesh.index().len()
        + 3 * mesh.positions().len()
        + mesh.values().len()) as u64
}

/// Refuses meshes whose words one storage binding cannot hold.
pub(super) fn check(ctx: &Context, total_words: u64) -> Result<(), RenderError> {
    let max = ctx
        .limits
        .max_storage_buffer_binding_size
        .min(ctx.limits.max_buffer_size);
    let bytes = 4 * total_words;
    if bytes > max || total_words > u64::from(u32::MAX) {
        return Err(RenderError::OutOfMemory {
            bytes,
            what: format!(
                "the unstructured fields' cells on {}, past the {max} bytes one buffer binds (render them on the CPU)",
                ctx.info.name
            ),
        });
    }
    Ok(())
}

/// Appends `mesh`'s words to `words`.
pub(super) fn pack(mesh: &UnstructuredVolume, words: &mut Vec<u32>) {
    let at = |parts: &[usize]| parts.iter().sum::<usize>() as u32;
    let nodes = 8 * mesh.nodes().len();
    let cells = mesh.cell_words().len();
    let index = mesh.index().len();
    let positions = 3 * mesh.positions().len();
    let (_, spacing) = mesh.lattice();
    let origin = mesh.bounds().0;
    words.extend([
        at(&[HEADER]),
        at(&[HEADER, nodes]),
        at(&[HEADER, nodes, cells]),
        at(&[HEADER, nodes, cells, index]),
        at(&[HEADER, nodes, cells, index, positions]),
        u32::from(mesh.per_vertex()),
    ]);
    words.extend(origin.to_array().map(f32::to_bits));
    words.extend(spacing.to_array().map(f32::to_bits));
    words.extend_from_slice(bytemuck::cast_slice(mesh.nodes()));
    words.extend_from_slice(mesh.cell_words());
    words.extend_from_slice(mesh.index());
    words.extend(
        mesh.positions()
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits)),
    );
    words.extend(mesh.values().iter().map(|v| v.to_bits()));
}
