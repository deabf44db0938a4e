//! The CPU's BVH builder: top-down, each node split where the surface
//! area heuristic over 16 bins of its primitives' centres is least (a
//! large node's bins filled from a sample), the two halves of a large
//! node built on two threads, each into its own range of one node array.
//! A subtree of at most `leaf` primitives is a leaf. It makes a tree the wide collapse takes
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

/// The tree over `items`, their numbers in its leaves'
/// `primitive_indices`; `items` end up in leaf order. `leaf` is rounded
/// down to a power of two. `None` where the nodes' memory cannot be had.
pub fn build(items: &mut [Item], leaf: usize) -> Option<Bvh2> {
    build_by(items, leaf, SAMPLED, STRIDE)
}

/// [`build`], nodes of more than `sampled` primitives choosing their
/// split from every `stride`th.
fn build_by(items: &mut [Item], leaf: usize, sampled: usize, stride: usize) -> Option<Bvh2> {
    if items.is_empty() {
        return Some(Bvh2::default());
    }
    let rules = Rules {
        leaf: 1 << leaf.max(1).ilog2(),
        sampled,
        stride: stride.max(1),
    };
    let span = items
        .par_chunks(CHUNK)
        .map(Span::of)
        .reduce(|| Span::EMPTY, Span::joined);
    // A tree whose every split leaves both sides non-empty has at most
    // 2n - 1 nodes. Each subtree fills a range of that bound from its
    // start, so threads write in place and nothing is joined after; the
    // unused rest stays zero pages the allocator never touched.
    let mut nodes = bytemuck::try_zeroed_slice_box::<Bvh2Node>(2 * items.len() - 1)
        .ok()?
        .into_vec();
    let (root, rest) = nodes.split_first_mut()?;
    subtree(items, span, 0, rules, (root, rest, 1));
    Some(Bvh2 {
        nodes,
        primitive_indices: items.iter().map(|i| i.index).collect(),
        ..Bvh2::default()
    })
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

/// Where a subtree's nodes go: its root, and a range of at least
/// 2n - 2 nodes for the rest, which starts at this index of the whole.
type Place<'a> = (&'a mut Bvh2Node, &'a mut [Bvh2Node], usize);

/// The subtree over `order` (which starts at `offset` of the whole, and
/// spans `span`), written to `place`; reorders `order` so each leaf's
/// primitives are contiguous.
fn subtree(order: &mut [Item], span: Span, offset: usize, rules: Rules, place: Place) {
    let (root, rest, base) = place;
    let aabb = |span: &Span| Aabb::new(span.bounds.lo, span.bounds.hi);
    if order.len() >= PARALLEL {
        if let Some((mid, l_span, r_span)) = split(order, &span, rules) {
            let (left, right) = order.split_at_mut(mid);
            // The two roots side by side, then each side's other nodes.
            let (roots, rest) = rest.split_at_mut(2);
            let (l_rest, r_rest) = rest.split_at_mut(2 * mid - 2);
            let [l_root, r_root] = roots else {
                unreachable!("two roots")
            };
            let r_base = base + 2 * mid;
            rayon::join(
                || subtree(left, l_span, offset, rules, (l_root, l_rest, base + 2)),
                || subtree(right, r_span, offset + mid, rules, (r_root, r_rest, r_base)),
            );
            *root = Bvh2Node::new(aabb(&span), 0, base as u32);
            return;
        }
    }
    // (node, range in `order`, its span); `None` is the root.
    let mut used = 0;
    let mut work = vec![(None, 0usize, order.len(), span)];
    while let Some((node, start, end, span)) = work.pop() {
        let made = match split(&mut order[start..end], &span, rules) {
            None => Bvh2Node::new(aabb(&span), (end - start) as u32, (offset + start) as u32),
            Some((mid, l_span, r_span)) => {
                let first = used;
                used += 2;
                work.push((Some(first), start, start + mid, l_span));
                work.push((Some(first + 1), start + mid, end, r_span));
                Bvh2Node::new(aabb(&span), 0, (base + first) as u32)
            }
        };
        match node {
            None => *root = made,
            Some(i) => rest[i] = made,
        }
    }
}

/// Per bin of one axis: the span of the primitives whose centres fall in
/// it.
type Bins = [Span; BINS];

/// Where to split `order` (of `span`), `order` partitioned so, with the
/// two sides' spans; `None` where it makes a leaf.
fn split(order: &mut [Item], span: &Span, rules: Rules) -> Option<(usize, Span, Span)> {
    let n = order.len();
    if n <= rules.leaf {
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
    // Twice the centre, against twice the lowest: one add an item.
    let binner = Binner {
        lo: 2.0 * lo,
        scale: 0.5 * BINS as f32 * (1.0 - 1e-6) / width,
    };
    // The axis a constant in each loop: its coordinate is one load.
    match axis {
        0 => binned::<0>(order, rules, binner),
        1 => binned::<1>(order, rules, binner),
        _ => binned::<2>(order, rules, binner),
    }
}

/// Where an item's centre falls among the bins of one axis.
#[derive(Clone, Copy)]
struct Binner {
    lo: f32,
    scale: f32,
}

impl Binner {
    #[inline(always)]
    fn bin<const AXIS: usize>(self, item: &Item) -> usize {
        let at = (item.lo[AXIS] + item.hi[AXIS] - self.lo) * self.scale;
        // max first: a NaN becomes bin 0. In [0, BINS - 1], so the
        // conversion is exact.
        // SAFETY: a finite float in [0, 15] fits a u32.
        unsafe { at.max(0.0).min((BINS - 1) as f32).to_int_unchecked::<u32>() as usize }
    }
}

/// [`split`] along axis `AXIS`, its centres spread over the bins by
/// `binner`.
fn binned<const AXIS: usize>(
    order: &mut [Item],
    rules: Rules,
    binner: Binner,
) -> Option<(usize, Span, Span)> {
    let (n, leaf) = (order.len(), rules.leaf);
    let bin = move |item: &Item| binner.bin::<AXIS>(item);
    // Neighbours mostly share a bin: two sets of bins, alternately
    // filled, keep each update from waiting for the last one's store.
    let fill = |items: &[Item]| {
        let mut bins: Bins = [Span::EMPTY; BINS];
        let mut odd: Bins = [Span::EMPTY; BINS];
        let pairs = items.chunks_exact(2);
        let last = pairs.remainder();
        for pair in pairs {
            bins[bin(&pair[0])].add(&pair[0]);
            odd[bin(&pair[1])].add(&pair[1]);
        }
        for item in last {
            bins[bin(item)].add(item);
        }
        for (x, y) in bins.iter_mut().zip(odd) {
            *x = x.joined(y);
        }
        bins
    };
    let all = |order: &[Item]| {
        if n >= 2 * CHUNK {
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
        }
    };
    if n > rules.sampled {
        // A large node's split is chosen from a sample of its primitives,
        // and the partition measures the two sides exactly: every
        // primitive is read once, not twice. Counts are all that is
        // sampled, so blocks are not rounded.
        let mut bins: Bins = [Span::EMPTY; BINS];
        for item in order.iter().step_by(rules.stride) {
            bins[bin(item)].add(item);
        }
        if let Some((b, _, _)) = cheapest(&bins, 1) {
            return Some(partition::<AXIS, true>(order, bin, b));
        }
        // The sample fell in one bin: every primitive is binned below.
    }
    let bins = all(order);
    let Some((b, left, right)) = cheapest(&bins, leaf) else {
        let (l, r) = order.split_at(n / 2);
        return Some((n / 2, Span::of(l), Span::of(r)));
    };
    let (mid, _, _) = partition::<AXIS, false>(order, bin, b);
    Some((mid, left, right))
}

/// How the tree is built: leaves of at most `leaf` primitives (a power of
/// two), nodes of more than `sampled` choosing their split from every
/// `stride`th.
#[derive(Clone, Copy)]
struct Rules {
    leaf: usize,
    sampled: usize,
    stride: usize,
}

/// Nodes of more primitives than this choose their split from every
/// [`STRIDE`]th of them. Sparser samples (a fixed 2048) missed the few
/// spheres beside a million triangles, and their boxes then swelled the
/// mesh's: 3-5 % slower frames.
const SAMPLED: usize = 1 << 13;
const STRIDE: usize = 8;

/// The first bin of the right side where the surface area heuristic over
/// `bins` is least, with the two sides' spans; `None` where every
/// primitive lies in one bin.
fn cheapest(bins: &Bins, leaf: usize) -> Option<(usize, Span, Span)> {
    // Leaves are tested a block of `leaf` at a time: counting blocks, not
    // primitives, favours sides that fill whole blocks (Embree's block
    // size), so leaves are full and hold fewer empty lanes. `leaf` is a
    // power of two: a shift, not a divide, in the sweep.
    let shift = leaf.trailing_zeros();
    let blocks = |n: usize| ((n + leaf - 1) >> shift) as f32;
    // The right sides' costs, swept from the last bin; boxes and counts
    // only, the spans made for the chosen split alone.
    let mut right = [(0.0f32, 0usize); BINS];
    let (mut acc, mut count) = (Bounds::EMPTY, 0);
    for b in (1..BINS).rev() {
        acc.grow(bins[b].bounds.lo, bins[b].bounds.hi);
        count += bins[b].count;
        right[b] = (acc.half_area() * blocks(count), count);
    }
    let (mut acc, mut count) = (Bounds::EMPTY, 0);
    let mut best: Option<(f32, usize)> = None;
    for b in 1..BINS {
        acc.grow(bins[b - 1].bounds.lo, bins[b - 1].bounds.hi);
        count += bins[b - 1].count;
        let (r_cost, r_count) = right[b];
        if count == 0 || r_count == 0 {
            continue;
        }
        let cost = acc.half_area() * blocks(count) + r_cost;
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, b));
        }
    }
    let (_, b) = best?;
    let side = |bins: &[Span]| bins.iter().fold(Span::EMPTY, |a, &s| a.joined(s));
    Some((b, side(&bins[..b]), side(&bins[b..])))
}

/// `order` partitioned: primitives of bins below `split` first, each pair
/// on the wrong sides swapped once. Returns where the right side starts
/// and, with `SPANS`, the two sides' spans (else empty spans).
fn partition<const AXIS: usize, const SPANS: bool>(
    order: &mut [Item],
    bin: impl Fn(&Item) -> usize,
    split: usize,
) -> (usize, Span, Span) {
    let (mut left, mut right) = (Span::EMPTY, Span::EMPTY);
    let (mut a, mut z) = (0, order.len());
    loop {
        while a < z && bin(&order[a]) < split {
            if SPANS {
                left.add(&order[a]);
            }
            a += 1;
        }
        while a < z && bin(&order[z - 1]) >= split {
            if SPANS {
                right.add(&order[z - 1]);
            }
            z -= 1;
        }
        if a + 1 >= z {
            break;
        }
        order.swap(a, z - 1);
        if SPANS {
            left.add(&order[a]);
            right.add(&order[z - 1]);
        }
        (a, z) = (a + 1, z - 1);
    }
    (a, left, right)
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
        holds_each_once(items);
        // Every eighth at one corner: the root's sample falls in one bin,
        // and the root bins every primitive instead.
        let corner = |index: u32| {
            let c = if index.is_multiple_of(8) {
                Vec3::ZERO
            } else {
                Vec3::splat(1.0) + Vec3::new(rnd(), rnd(), rnd()) * 10.0
            };
            Item {
                lo: c,
                index,
                hi: c + 0.01,
            }
        };
        holds_each_once((0..16_384).map(corner).collect());
        // None: an empty tree.
        assert!(build(&mut [], 8).is_some_and(|b| b.nodes.is_empty()));
    }

    /// `items`' tree holds every one of them in exactly one leaf, every
    /// node's box around its children's, no leaf over eight.
    fn holds_each_once(mut items: Vec<Item>) {
        let given = items.clone();
        let bvh = build(&mut items, 8).expect("memory for the nodes");
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

    /// The surface area heuristic's cost of `bvh` (traversal steps 1, a
    /// block of `leaf` primitives of one kind 1; primitives numbered from
    /// `first_other` are of another kind), relative to its root's area.
    fn sah_cost(bvh: &Bvh2, leaf: usize, first_other: u32) -> f64 {
        let root = f64::from(bvh.nodes[0].aabb.half_area());
        let (mut cost, mut stack) = (0.0, vec![0usize]);
        while let Some(i) = stack.pop() {
            let n = &bvh.nodes[i];
            let area = f64::from(n.aabb.half_area()) / root;
            if n.prim_count > 0 {
                let first = n.first_index as usize;
                let prims = &bvh.primitive_indices[first..first + n.prim_count as usize];
                let others = prims.iter().filter(|&&p| p >= first_other).count();
                let blocks = (prims.len() - others).div_ceil(leaf) + others.div_ceil(leaf);
                cost += area * blocks as f64;
            } else {
                cost += area;
                let f = n.first_index as usize;
                stack.extend([f, f + 1]);
            }
        }
        cost
    }

    /// A large mesh with a few small things around it, as hosts send: a
    /// tree whose large nodes split by a sample costs what one binning
    /// every primitive costs (within 0.5 %); sixteen samples a node, too
    /// few to see the few, build one that costs more.
    #[test]
    fn a_sampled_split_sees_the_few_primitives_beside_many() {
        let mut items = Vec::new();
        let q = 400u32;
        let at = |th: f32, ph: f32, r: f32| {
            Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * r
        };
        for i in 0..q {
            for j in 0..q {
                let th = std::f32::consts::PI * (i as f32 + 0.5) / q as f32;
                let ph = std::f32::consts::TAU * j as f32 / q as f32;
                let (a, b) = (at(th, ph, 1.0), at(th + 0.008, ph + 0.016, 1.0));
                let index = items.len() as u32;
                items.push(Item {
                    lo: a.min(b),
                    index,
                    hi: a.max(b),
                });
            }
        }
        let first_other = items.len() as u32;
        for k in 0..1024u32 {
            let th = std::f32::consts::PI * ((k / 32) as f32 + 0.5) / 32.0;
            let ph = std::f32::consts::TAU * (k % 32) as f32 / 32.0;
            let c = at(th, ph, 1.35);
            let index = items.len() as u32;
            items.push(Item {
                lo: c - 0.04,
                index,
                hi: c + 0.04,
            });
        }
        let cost = |sampled: usize, stride: usize| {
            let mut order = items.clone();
            let bvh = build_by(&mut order, 8, sampled, stride).expect("memory for the nodes");
            sah_cost(&bvh, 8, first_other)
        };
        let every = cost(usize::MAX, STRIDE);
        let sampled = cost(SAMPLED, STRIDE);
        let sparse = cost(SAMPLED, items.len() / 16);
        assert!(sampled <= 1.005 * every, "{sampled} against {every}");
        assert!(sparse > 1.005 * every, "{sparse} against {every}");
    }
}
