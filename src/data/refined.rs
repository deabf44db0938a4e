//! Procedural AMR fields over [-1, 1]^3, with the structured grid of the
//! same function at the finest resolution beside them: what the tests
//! compare and the benchmarks march.

use glam::{IVec3, UVec3, Vec3};

use crate::scene::{AmrBlock, AmrError, AmrInput, AmrVolume, StructuredVolume, Voxels};

/// Cells per block edge at most, as FLASH's blocks (nxb = 8) and AMReX's
/// blocking factors cut levels.
const BLOCK: i32 = 8;

/// A smooth field over [-1, 1]^3 in [0, 1]: waves whose features span a
/// few coarse cells, so every level resolves them, fading to 0 towards
/// the box's faces (where a grid of cell centres and one of vertices
/// would end half a cell apart).
pub fn smooth_waves(p: Vec3) -> f32 {
    let r = p.length();
    let waves = 0.5 + 0.25 * (5.0 * r).sin() + 0.25 * (3.0 * p.x).cos() * (2.0 * p.y + p.z).sin();
    let edge = ((0.9 - p.abs().max_element()) / 0.25).clamp(0.0, 1.0);
    (waves * edge * edge * (3.0 - 2.0 * edge)).clamp(0.0, 1.0)
}

/// An AMR field of `f` over [-1, 1]^3: `levels` levels, level 0 the
/// finest with `n` cells across the whole box (n a multiple of
/// 2^levels * 8), each level refining the middle half of the one above
/// it; the coarsest covers the box. Every level holds its whole box,
/// parents under children, cut into blocks of at most 8^3 cells.
pub fn refined(n: u32, levels: u32, f: impl Fn(Vec3) -> f32) -> Result<AmrVolume, AmrError> {
    let levels = levels.clamp(1, 8);
    let n = n as i32;
    let h = 2.0 / n as f32;
    let mut blocks = Vec::new();
    let mut values = Vec::new();
    for level in 0..levels {
        let w = 1 << level;
        // Half the box's extent per level up from the finest, in
        // finest cells; the coarsest covers it all.
        let half = if level + 1 == levels {
            n / 2
        } else {
            (n / 2) >> (levels - 1 - level)
        };
        let (lo, hi) = ((n / 2 - half) / w, (n / 2 + half) / w - 1);
        let mut z = lo;
        while z <= hi {
            let mut y = lo;
            while y <= hi {
                let mut x = lo;
                while x <= hi {
                    let b0 = IVec3::new(x, y, z);
                    let b1 = (b0 + IVec3::splat(BLOCK - 1)).min(IVec3::splat(hi));
                    blocks.push(AmrBlock {
                        lo: b0,
                        hi: b1,
                        level,
                    });
                    for k in b0.z..=b1.z {
                        for j in b0.y..=b1.y {
                            for i in b0.x..=b1.x {
                                let c = (IVec3::new(i, j, k).as_vec3() + 0.5) * w as f32;
                                values.push(f(c * h - Vec3::ONE));
                            }
                        }
                    }
                    x += BLOCK;
                }
                y += BLOCK;
            }
            z += BLOCK;
        }
    }
    AmrVolume::new(AmrInput {
        widths: (0..levels).map(|l| (1u32 << l) as f32).collect(),
        blocks,
        values,
        origin: Vec3::splat(-1.0),
        spacing: Vec3::splat(h),
    })
}

/// `f` on the grid of the finest cells' centres of [`refined`]`(n, ..)`:
/// n^3 vertices from -1 + h / 2 to 1 - h / 2.
pub fn finest_grid(n: u32, f: impl Fn(Vec3) -> f32) -> StructuredVolume {
    let h = 2.0 / n as f32;
    let mut values = Vec::with_capacity((n * n * n) as usize);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let c = (UVec3::new(x, y, z).as_vec3() + 0.5) * h - Vec3::ONE;
                values.push(f(c));
            }
        }
    }
    StructuredVolume::new(
        UVec3::splat(n),
        Voxels::F32(values.into()),
        Vec3::splat(-1.0 + h / 2.0),
        Vec3::splat(h),
    )
    .expect("the finest grid is valid by construction")
}
