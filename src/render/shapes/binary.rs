//! The GPU's traversal of the binary BVH, run on the CPU: surface.wgsl's
//! `nearest_surface` step for step (its box test, its order, its stack),
//! so that what the tests and benchmarks check of the binary tree is what
//! the GPU runs.

use glam::Vec3;
use obvhs::bvh2::Bvh2;

use super::wide::ROBUST;

/// surface.wgsl's `safe_inverse`: 1 / x, tiny components held off zero.
fn safe_inverse(x: f32) -> f32 {
    if x.abs() < 1e-20 {
        1.0 / if x < 0.0 { -1e-20 } else { 1e-20 }
    } else {
        1.0 / x
    }
}

/// Where `o + t d` enters the box `[lo, hi]` within `(t_min, t_max)`, or
/// infinity; the far distance stretched as the wide tree's is, so a ray
/// through a box's face or corner is not lost to rounding.
fn box_entry(o: Vec3, inv: Vec3, (lo, hi): (Vec3, Vec3), t_min: f32, t_max: f32) -> f32 {
    let ta = (lo - o) * inv;
    let tb = (hi - o) * inv;
    let (tn, tf) = (ta.min(tb), ta.max(tb));
    let near = tn.x.max(tn.y).max(tn.z).max(t_min);
    let far = tf.x.min(tf.y).min(tf.z).min(t_max) * ROBUST;
    if near <= far {
        near
    } else {
        f32::INFINITY
    }
}

/// The nearest hit with `t` in `(t_min, t_max)` along `o + t d`: the
/// position in `bvh.primitive_indices` and what `test(position, t_max)`
/// gave, which answers a primitive's first hit in `(t_min, t_max)` and
/// its distance. Nodes past `stack_max` deep are dropped, as the GPU's fixed
/// stack drops them (packed.rs refuses trees that deep).
pub fn closest<T>(
    bvh: &Bvh2,
    (o, d): (Vec3, Vec3),
    (t_min, t_max): (f32, f32),
    stack_max: usize,
    mut test: impl FnMut(u32, f32) -> Option<(f32, T)>,
) -> Option<(u32, f32, T)> {
    let nodes = &bvh.nodes;
    if nodes.is_empty() || t_max.partial_cmp(&t_min) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let bounds = |i: u32| {
        let b = &nodes[i as usize].aabb;
        (Vec3::from(b.min), Vec3::from(b.max))
    };
    let inv = Vec3::new(safe_inverse(d.x), safe_inverse(d.y), safe_inverse(d.z));
    let mut limit = t_max;
    let mut best = None;
    if box_entry(o, inv, bounds(0), t_min, limit) == f32::INFINITY {
        return None;
    }
    let mut stack: Vec<(u32, f32)> = Vec::with_capacity(stack_max);
    let mut node = 0u32;
    loop {
        let n = &nodes[node as usize];
        let first = n.first_index;
        if n.prim_count > 0 {
            for j in first..first + n.prim_count {
                if let Some((t, found)) = test(j, limit).filter(|&(t, _)| t < limit) {
                    limit = t;
                    best = Some((j, t, found));
                }
            }
        } else {
            let ta = box_entry(o, inv, bounds(first), t_min, limit);
            let tb = box_entry(o, inv, bounds(first + 1), t_min, limit);
            let b_first = tb < ta;
            let (near, far) = (ta.min(tb), ta.max(tb));
            if near < f32::INFINITY {
                if far < f32::INFINITY && stack.len() < stack_max {
                    stack.push((if b_first { first } else { first + 1 }, far));
                }
                node = if b_first { first + 1 } else { first };
                continue;
            }
        }
        // The next node kept that a nearer hit has not ruled out.
        let mut next = None;
        while let Some((kept, entry)) = stack.pop() {
            if entry < limit {
                next = Some(kept);
                break;
            }
        }
        match next {
            Some(kept) => node = kept,
            None => return best,
        }
    }
}
