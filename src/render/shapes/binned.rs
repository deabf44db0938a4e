//! The CPU's BVH builder: top-down, each node split where the surface
//! area heuristic over 16 bins of its primitives' centres is least, the
//! two halves of a large node built on two threads. A subtree of at most
//! `leaf` primitives is a leaf. It makes a tree the wide collapse takes
//! (wide.rs) in a fraction of the time and memory of a PLOC build (the
//! GPU's), whose finer tree the wide nodes would flatten anyway.

use glam::{Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::Bvh2;
use rayon::prelude::*;

const BINS: usize = 16;

/// Ranges at least this long split their two halves between threads.
const PARALLEL: usize = 1 << 14;

/// A primitive's box and its number. The builder moves these, not
/// indices to them: each pass over a node's primitives then reads memory
/// in order.
#[derive(Clone, Copy)]
#[repr(C, align(16))]
pub struct Item {
    pub lo: Vec3,
    pub index: u32,
    pub hi: Vec3,
}

/// A box, in SIMD vectors: growing one is two instructions.
#[derive(Clone, Copy)]
struct Bounds {
    lo: Vec3A,
    hi: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        lo: Vec3A::INFINITY,
        hi: Vec3A::NEG_INFINITY,
    };

    fn grow(&mut self, lo: Vec3A, hi: Vec3A) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
    }

    fn half_area(&self) -> f32 {
        let e = (self.hi - self.lo).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// An item's box and centre.
fn corners(item: &Item) -> (Vec3A, Vec3A, Vec3A) {
    let (lo, hi) = (Vec3A::from(item.lo), Vec3A::from(item.hi));
    (lo, hi, (lo + hi) * 0.5)
}

/// The tree over `items` (at least one), their numbers in its leaves'
/// `primitive_indices`; `items` end up in leaf order.
pub fn build(items: &mut [Item], leaf: usize) -> Bvh2 {
    let span = items
        .par_chunks(CHUNK)
        .map(Span::of)
        .reduce(|| Span::EMPTY, Span::joined);
    let nodes = subtree(items, span, 0, leaf.max(1));
    Bvh2 {
        nodes,
        primitive_indices: items.iter().map(|i| i.index).collect(),
        ..Bvh2::default()
    }
}

/// Ranges at least this long are binned on several threads, in chunks of
/// this many.
const CHUNK: usize = 1 << 16;

/// The box around some primitives and the box around their centres:
/// what each node's split needs, handed down from its parent's bins so
/// that a node reads its primitives twice (binning, partition), not three
/// times.
#[derive(Clone, Copy)]
struct Span {
    bounds: Bounds,
    centres: Bounds,
    count: usize,
}

impl Span {
    const EMPTY: Span = Span {
        bounds: Bounds::EMPTY,
        centres: Bounds::EMPTY,
        count: 0,
    };

    fn add(&mut self, item: &Item) {
        let (lo, hi, c) = corners(item);
        self.bounds.grow(lo, hi);
        self.centres.grow(c, c);
        self.count += 1;
    }

    fn of(items: &[Item]) -> Span {
        let mut span = Span::EMPTY;
        for item in items {
            span.add(item);
        }
        span
    }

    fn joined(mut self, other: Span) -> Span {
        self.bounds.grow(other.bounds.lo, other.bounds.hi);
        self.centres.grow(other.centres.lo, other.centres.hi);
        self.count += other.count;
        self
    }
}

/// The nodes of the subtree over `order` (which starts at `offset` of the
/// whole, and spans `span`), its root first; reorders `order` so each
/// leaf's primitives are contiguous.
fn subtree(order: &mut [Item], span: Span, offset: usize, leaf: usize) -> Vec<Bvh2Node> {
    if order.len() >= PARALLEL {
        if let Some((mid, l_span, r_span)) = split(order, &span, leaf) {
            let (left, right) = order.split_at_mut(mid);
            let (l, r) = rayon::join(
                || subtree(left, l_span, offset, leaf),
                || subtree(right, r_span, offset + mid, leaf),
            );
            return joined(span.bounds, l, r);
        }
    }
    // (node, range in `order`, its span), the node already pushed.
    let mut nodes = vec![Bvh2Node::default()];
    let mut work = vec![(0usize, 0usize, order.len(), span)];
    while let Some((node, start, end, span)) = work.pop() {
        let aabb = Aabb::new(span.bounds.lo, span.bounds.hi);
        nodes[node] = match split(&mut order[start..end], &span, leaf) {
            None => Bvh2Node::new(aabb, (end - start) as u32, (offset + start) as u32),
            Some((mid, l_span, r_span)) => {
                let first = nodes.len();
                nodes.extend([Bvh2Node::default(); 2]);
                work.push((first, start, start + mid, l_span));
                work.push((first + 1, start + mid, end, r_span));
                Bvh2Node::new(aabb, 0, first as u32)
            }
        };
    }
    nodes
}

/// A root over subtrees `l` and `r` (each root first), their nodes after
/// it and their child indices moved to match.
fn joined(bounds: Bounds, l: Vec<Bvh2Node>, r: Vec<Bvh2Node>) -> Vec<Bvh2Node> {
    let (ln, rn) = (l.len(), r.len());
    // Local index k > 0 of the left subtree lands at 2 + k, of the right
    // at 2 + (ln - 1) + k; the roots at 1 and 2.
    let moved = |n: Bvh2Node, shift: usize| {
        if n.prim_count > 0 {
            n
        } else {
            Bvh2Node {
                first_index: n.first_index + shift as u32,
                ..n
            }
        }
    };
    let mut nodes = Vec::with_capacity(1 + ln + rn);
    let aabb = Aabb::new(bounds.lo, bounds.hi);
    nodes.push(Bvh2Node::new(aabb, 0, 1));
    nodes.push(moved(l[0], 2));
    nodes.push(moved(r[0], 1 + ln));
    nodes.extend(l[1..].iter().map(|&n| moved(n, 2)));
    nodes.extend(r[1..].iter().map(|&n| moved(n, 1 + ln)));
    nodes
}

/// Per bin of one axis: the span of the primitives whose centres fall in
/// it.
type Bins = [Span; BINS];

/// Where to split `order` (of `span`), `order` partitioned so, with the
/// two sides' spans; `None` where it makes a leaf.
fn split(order: &mut [Item], span: &Span, leaf: usize) -> Option<(usize, Span, Span)> {
    let n = order.len();
    if n <= leaf {
        return None;
    }
    let extent = Vec3::from(span.centres.hi - span.centres.lo);
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let (lo, width) = (span.centres.lo[axis], extent[axis]);
    if width.is_nan() || width <= 0.0 {
        // Every centre at one point: halves by count.
        let (l, r) = order.split_at(n / 2);
        return Some((n / 2, Span::of(l), Span::of(r)));
    }
    let scale = BINS as f32 * (1.0 - 1e-6) / width;
    let top = (BINS - 1) as f32;
    let bin = |item: &Item| {
        let at = (corners(item).2[axis] - lo) * scale;
        // max first: a NaN becomes bin 0. In [0, BINS - 1], so the
        // conversion is exact.
        // SAFETY: a finite float in [0, 15] fits a u32.
        unsafe { at.max(0.0).min(top).to_int_unchecked::<u32>() as usize }
    };
    let fill = |items: &[Item]| {
        let mut bins: Bins = [Span::EMPTY; BINS];
        for item in items {
            bins[bin(item)].add(item);
        }
        bins
    };
    let bins = if n >= 2 * CHUNK {
        order.par_chunks(CHUNK).map(fill).reduce(
            || [Span::EMPTY; BINS],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    *x = x.joined(y);
                }
                a
            },
        )
    } else {
        fill(order)
    };
    // Costs of the right sides, swept from the last bin.
    let mut right = [Span::EMPTY; BINS];
    let mut acc = Span::EMPTY;
    for b in (1..BINS).rev() {
        acc = acc.joined(bins[b]);
        right[b] = acc;
    }
    let mut acc = Span::EMPTY;
    let mut best: Option<(f32, usize, Span)> = None;
    for b in 1..BINS {
        acc = acc.joined(bins[b - 1]);
        let r = &right[b];
        if acc.count == 0 || r.count == 0 {
            continue;
        }
        // Leaves are tested a block of `leaf` at a time: counting blocks,
        // not primitives, favours sides that fill whole blocks (Embree's
        // block size), so leaves are full and hold fewer empty lanes.
        let blocks = |n: usize| n.div_ceil(leaf) as f32;
        let cost =
            acc.bounds.half_area() * blocks(acc.count) + r.bounds.half_area() * blocks(r.count);
        if best.is_none_or(|(c, _, _)| cost < c) {
            best = Some((cost, b, acc));
        }
    }
    let Some((_, b, left)) = best else {
        let (l, r) = order.split_at(n / 2);
        return Some((n / 2, Span::of(l), Span::of(r)));
    };
    // Partition: primitives of bins below the split first, each pair on
    // the wrong sides swapped once.
    let (mut a, mut z) = (0, n);
    loop {
        while a < z && bin(&order[a]) < b {
            a += 1;
        }
        while a < z && bin(&order[z - 1]) >= b {
            z -= 1;
        }
        if a + 1 >= z {
            break;
        }
        order.swap(a, z - 1);
        (a, z) = (a + 1, z - 1);
    }
    Some((a, left, right[b]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every primitive in exactly one leaf, every node's box around its
    /// children's, leaves no larger than asked.
    #[test]
    fn the_tree_holds_every_primitive_once_within_its_boxes() {
        let mut seed = 7u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut items: Vec<Item> = (0..40_000)
            .map(|index| {
                let c = Vec3::new(rnd(), rnd(), rnd()) * 10.0;
                let r = Vec3::splat(0.01 + 0.1 * rnd());
                Item {
                    lo: c - r,
                    index,
                    hi: c + r,
                }
            })
            .collect();
        // Many at one point, to split by count.
        items.extend((40_000..40_100).map(|index| Item {
            lo: Vec3::ONE,
            index,
            hi: Vec3::ONE,
        }));
        let given = items.clone();
        let bvh = build(&mut items, 8);
        let items = given;
        let mut seen = vec![0u32; items.len()];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &bvh.nodes[i];
            let (lo, hi) = (Vec3::from(n.aabb.min), Vec3::from(n.aabb.max));
            if n.prim_count > 0 {
                assert!(n.prim_count <= 8);
                let first = n.first_index as usize;
                for &p in &bvh.primitive_indices[first..first + n.prim_count as usize] {
                    seen[p as usize] += 1;
                    let item = &items[p as usize];
                    assert!(item.lo.cmpge(lo).all() && item.hi.cmple(hi).all());
                }
                continue;
            }
            for c in [n.first_index as usize, n.first_index as usize + 1] {
                let child = &bvh.nodes[c].aabb;
                assert!(Vec3::from(child.min).cmpge(lo).all());
                assert!(Vec3::from(child.max).cmple(hi).all());
                stack.push(c);
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }
}
