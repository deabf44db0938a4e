//! Unstructured fields on the GPU: each mesh laid out as u32 words in one
//! storage buffer (`meshes`), which shaders/volume.wgsl reads where a
//! volume slot's sampling is FILTER_CELLS.
//!
//! One mesh, from its first word m, offsets relative to m:
//! - m + 0..5: where its nodes, cells, index, positions and values begin;
//! - m + 5: 1 where values are per vertex, 0 per cell;
//! - m + 6..9: its lattice's origin, m + 9..12: the lattice spacing (f32);
//! - m + 12: where the tetrahedra's walk begins (0: the mesh has none);
//! - nodes, 8 words each: box min (3 f32), first, box max (3 f32), count
//!   (scene::MeshNode);
//! - cells in BVH order, one word each: first index << 2 | kind code;
//! - the index; positions, 3 f32 each; values, one f32 each;
//! - the walk, WALK_WORDS a cell in BVH order (scene::tet_walk).

use super::context::Context;
use crate::render::RenderError;
use crate::scene::{UnstructuredVolume, WALK_WORDS};

/// Words before a mesh's nodes.
const HEADER: usize = 13;

/// Words of the mesh's walk: one record a cell, where it has tetrahedra.
fn walk_len(mesh: &UnstructuredVolume) -> usize {
    if mesh.walk_words().is_some() {
        WALK_WORDS * mesh.cell_count()
    } else {
        0
    }
}

/// Words `mesh` takes in the buffer.
pub(super) fn word_count(mesh: &UnstructuredVolume) -> u64 {
    (HEADER
        + 8 * mesh.nodes().len()
        + mesh.cell_words().len()
        + mesh.index().len()
        + 3 * mesh.positions().len()
        + mesh.values().len()
        + walk_len(mesh)) as u64
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
                "the unstructured and AMR fields' cells on {}, past the {max} bytes one buffer binds (render them on the CPU)",
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
    let values = mesh.values().len();
    words.push(if walk_len(mesh) > 0 {
        at(&[HEADER, nodes, cells, index, positions, values])
    } else {
        0
    });
    words.extend_from_slice(bytemuck::cast_slice(mesh.nodes()));
    words.extend_from_slice(mesh.cell_words());
    words.extend_from_slice(mesh.index());
    words.extend(
        mesh.positions()
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits)),
    );
    words.extend(mesh.values().iter().map(|v| v.to_bits()));
    if let Some(walk) = mesh.walk_words() {
        words.extend(walk);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{MeshInput, MeshValues};
    use glam::Vec3;

    #[test]
    fn the_words_packed_are_the_words_counted_with_and_without_a_walk() {
        let hexahedron = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
            Vec3::Z,
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::ONE,
            Vec3::new(0.0, 1.0, 1.0),
        ];
        let mesh = |types: Vec<u32>| {
            let (positions, index, cell_index) = if types[0] == 10 {
                (
                    vec![hexahedron[0], hexahedron[1], hexahedron[3], hexahedron[4]],
                    vec![0, 1, 2, 3],
                    vec![0],
                )
            } else {
                (hexahedron.to_vec(), (0..8).collect(), vec![0])
            };
            let n = positions.len();
            UnstructuredVolume::new(
                MeshInput {
                    positions,
                    index,
                    cell_index,
                    cell_type: types,
                },
                MeshValues::PerVertex(vec![0.5; n]),
            )
            .unwrap()
        };
        for (m, walk) in [(mesh(vec![10]), true), (mesh(vec![12]), false)] {
            let mut words = vec![7u32; 3];
            pack(&m, &mut words);
            assert_eq!(words.len() as u64 - 3, word_count(&m));
            let header = &words[3..];
            // The walk's offset, and its records at the end.
            assert_eq!(header[12] != 0, walk);
            if walk {
                assert_eq!(
                    header[12] as usize + WALK_WORDS * m.cell_count(),
                    header.len()
                );
                // The one tetrahedron can hold points; no neighbours.
                assert_eq!(header[header.len() - 1], 1);
                assert_eq!(header[header.len() - 5..header.len() - 1], [u32::MAX; 4]);
            }
        }
    }
}
