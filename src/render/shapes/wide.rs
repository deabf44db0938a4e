//! The CPU's traversal of a shape set: the binary BVH collapsed into nodes
//! of eight children whose boxes one ray tests at once, over leaves whose
//! triangles sit in world space eight to a block, also tested at once
//! (the watertight test of intersect.rs with its arithmetic, lane by
//! lane, so both find the same hits to the bit). Spheres, cones, curves,
//! and triangles whose opacity can hide parts of them stay in a leaf's
//! list for the caller to test one by one.
//!
//! The kernels are plain loops over eight lanes, one body built for each
//! SIMD level (simd.rs): the compiler turns each loop into one vector
//! instruction per operation on AVX2 and AVX-512, two on the baseline.

use std::mem::MaybeUninit;

use glam::{Vec2, Vec3};
use obvhs::bvh2::Bvh2;
use rayon::prelude::*;

use super::intersect::Shear;
use super::pages::ask_huge;
use crate::render::simd::Level;

/// Children per node, triangles per block.
pub const WIDTH: usize = 8;

/// The most primitives the binary tree's leaves should hold: one block.
pub const LEAF_MAX: u32 = 8;

/// A child reference with this bit set is a leaf's index.
const LEAF: u32 = 1 << 31;

/// A child slot with nothing in it (its box is empty and never hit).
const EMPTY: u32 = u32::MAX;

/// A box's far distance is stretched by this much, so that rounding in
/// the slab test cannot make a ray miss a box it grazes (Ize, "Robust
/// BVH Ray Traversal", 2013: 1 + 2 gamma(3)).
pub const ROBUST: f32 = 1.0 + 3.0 * f32::EPSILON;

/// Eight children's boxes, an axis at a time, and what each child is.
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Node {
    lo: [[f32; WIDTH]; 3],
    hi: [[f32; WIDTH]; 3],
    child: [u32; WIDTH],
}

const EMPTY_NODE: Node = Node {
    lo: [[f32::INFINITY; WIDTH]; 3],
    hi: [[f32::NEG_INFINITY; WIDTH]; 3],
    child: [EMPTY; WIDTH],
};

/// Eight triangles in world space, their corners an axis at a time (the
/// corners themselves, not edges from one of them: the watertight test
/// needs each edge from its own two corners); lanes past the leaf's last
/// triangle have three equal corners (a zero determinant, never hit).
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Block {
    a: [[f32; WIDTH]; 3],
    b: [[f32; WIDTH]; 3],
    c: [[f32; WIDTH]; 3],
    /// The shape set's primitive in each lane.
    prim: [u32; WIDTH],
}

const EMPTY_BLOCK: Block = Block {
    a: [[0.0; WIDTH]; 3],
    b: [[0.0; WIDTH]; 3],
    c: [[0.0; WIDTH]; 3],
    prim: [EMPTY; WIDTH],
};

/// Eight spheres in world space: centres an axis at a time, radii;
/// lanes past the leaf's last sphere have radius -1 (never hit).
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Ball {
    c: [[f32; WIDTH]; 3],
    r: [f32; WIDTH],
    prim: [u32; WIDTH],
}

const EMPTY_BALL: Ball = Ball {
    c: [[0.0; WIDTH]; 3],
    r: [-1.0; WIDTH],
    prim: [EMPTY; WIDTH],
};

/// A leaf's triangle blocks, sphere blocks and its primitives tested one
/// by one.
#[derive(Clone, Copy, Default)]
struct Leaf {
    block: u32,
    blocks: u32,
    ball: u32,
    balls: u32,
    other: u32,
    others: u32,
}

/// How a leaf tests a primitive.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// In a block of triangles, corners in world space.
    Triangle,
    /// In a block of spheres, centre and radius in world space.
    Sphere,
    /// One by one, by the caller's test.
    Other,
}

/// What the collapse needs to know of the primitives.
pub trait Primitives: Sync {
    fn kind(&self, p: u32) -> Kind;
    /// A [`Kind::Triangle`]'s corners.
    fn triangle(&self, p: u32) -> [Vec3; 3];
    /// A [`Kind::Sphere`]'s centre and radius.
    fn sphere(&self, p: u32) -> (Vec3, f32);
}

/// The nearest hit a traversal found: the shape set's primitive, the ray
/// parameter and the barycentrics (a triangle's) or what the caller's
/// test gave, and for a triangle its facing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Found {
    pub prim: u32,
    pub t: f32,
    pub bary: Vec2,
    /// A triangle's (b - a) x (c - a) in world space, taken from its
    /// block while that is in cache: the shading then need not fetch its
    /// three vertices again.
    pub facing: Option<Vec3>,
}

/// A shape set's wide BVH.
#[derive(Default)]
pub struct Wide {
    nodes: Vec<Node>,
    blocks: Vec<Block>,
    balls: Vec<Ball>,
    leaves: Vec<Leaf>,
    others: Vec<u32>,
    /// The root's reference (a node, a leaf, or EMPTY).
    root: u32,
    /// Stack entries a traversal may need.
    stack: usize,
}

/// What a traversal knows of its ray.
struct Ray {
    o: Vec3,
    d: Vec3,
    /// 1 / d, with zero components replaced by the smallest normal float
    /// of their sign so that no slab distance is 0 * inf.
    inv: [f32; 3],
    /// Whether each component of d is negative: then the box's far plane
    /// on that axis is its low one.
    neg: [bool; 3],
    shear: Shear,
}

impl Ray {
    fn new(o: Vec3, d: Vec3) -> Ray {
        let safe = |c: f32| {
            if c.abs() < f32::MIN_POSITIVE {
                1.0 / f32::MIN_POSITIVE.copysign(c)
            } else {
                1.0 / c
            }
        };
        let inv = [safe(d.x), safe(d.y), safe(d.z)];
        Ray {
            o,
            d,
            inv,
            // From the inverse: a component of -0 has a negative one.
            neg: inv.map(|i| i < 0.0),
            shear: Shear::of(d),
        }
    }
}

/// `max` and `min` as one compare and select, the same on every level.
#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

impl Wide {
    /// `bvh` collapsed, its primitives numbered as its
    /// `primitive_indices` hold them and told apart by `prims`. Each
    /// binary leaf becomes a leaf (binned.rs makes them of up to LEAF_MAX
    /// primitives). The root's children are collapsed on several
    /// threads, straight into their parts of arrays counted and allocated
    /// once.
    pub fn collapse(bvh: &Bvh2, prims: &impl Primitives) -> Wide {
        if bvh.nodes.is_empty() {
            return Wide {
                root: EMPTY,
                ..Wide::default()
            };
        }
        let (root, kids) = if bvh.nodes[0].prim_count > 0 {
            (
                None,
                Kids {
                    kids: [0; WIDTH],
                    len: 1,
                },
            )
        } else {
            let (node, kids) = Self::opened(bvh, 0);
            (Some(node), kids)
        };
        let sizes: Vec<Sizes> = kids.par_iter().map(|&k| Sizes::of(bvh, k, prims)).collect();
        let total = sizes.iter().fold(Sizes::default(), |a, b| a.plus(b));
        let top = usize::from(root.is_some());
        // Allocated once and left unwritten: every element is written
        // exactly once below (the parts fill what Sizes counted, which
        // they assert), and a million triangles' blocks are 45 MB that a
        // first fill would write twice.
        let mut all_nodes = Box::new_uninit_slice(top + total.nodes);
        let mut all_blocks = Box::new_uninit_slice(total.blocks);
        let mut all_balls = Box::new_uninit_slice(total.balls);
        let mut all_leaves = Box::new_uninit_slice(total.leaves);
        let mut all_others = Box::new_uninit_slice(total.others);
        ask_huge(&mut all_nodes);
        ask_huge(&mut all_blocks);
        // Each part's slices of the arrays, and where they start.
        let mut parts = Vec::with_capacity(kids.len());
        let (mut nodes, mut blocks) = (&mut all_nodes[top..], &mut all_blocks[..]);
        let (mut leaves, mut others) = (&mut all_leaves[..], &mut all_others[..]);
        let mut balls = &mut all_balls[..];
        let mut base = Sizes {
            nodes: top,
            ..Sizes::default()
        };
        for (&k, size) in kids.iter().zip(&sizes) {
            let (n, rest_n) = std::mem::take(&mut nodes).split_at_mut(size.nodes);
            let (b, rest_b) = std::mem::take(&mut blocks).split_at_mut(size.blocks);
            let (l, rest_l) = std::mem::take(&mut leaves).split_at_mut(size.leaves);
            let (o, rest_o) = std::mem::take(&mut others).split_at_mut(size.others);
            let (s, rest_s) = std::mem::take(&mut balls).split_at_mut(size.balls);
            (nodes, blocks, leaves, others, balls) = (rest_n, rest_b, rest_l, rest_o, rest_s);
            parts.push((k, size, Out::new(n, (b, s), l, o, base)));
            base = base.plus(size);
        }
        let roots: Vec<u32> = parts
            .into_par_iter()
            .map(|(k, size, mut out)| {
                let root = out.part(bvh, k, prims);
                assert!(
                    out.filled.same_counts(size),
                    "the wide collapse filled other sizes than it counted"
                );
                root
            })
            .collect();
        let mut root_ref = 0;
        match root {
            Some(mut node) => {
                node.child[..roots.len()].copy_from_slice(&roots);
                all_nodes[0].write(node);
            }
            None => root_ref = roots[0],
        }
        // SAFETY: the parts wrote every element of their slices (asserted
        // above), and the root node, where there is one, is written.
        let (nodes, blocks, balls, leaves, others) = unsafe {
            (
                all_nodes.assume_init(),
                all_blocks.assume_init(),
                all_balls.assume_init(),
                all_leaves.assume_init(),
                all_others.assume_init(),
            )
        };
        Wide {
            nodes: nodes.into_vec(),
            blocks: blocks.into_vec(),
            balls: balls.into_vec(),
            leaves: leaves.into_vec(),
            others: others.into_vec(),
            root: root_ref,
            stack: (WIDTH - 1) * (top + total.deepest) + 1,
        }
    }

    /// A wide node over binary inner node `i`, and the binary nodes its
    /// slots stand for: the largest child that is no leaf is opened until
    /// there are eight, so the boxes a ray is likeliest to enter are split
    /// the finest. Its children are left EMPTY.
    fn opened(bvh: &Bvh2, i: u32) -> (Node, Kids) {
        let nodes = &bvh.nodes;
        let n = &nodes[i as usize];
        let mut kids = [0; WIDTH];
        (kids[0], kids[1]) = (n.first_index, n.first_index + 1);
        let mut k = 2;
        while k < WIDTH {
            let area = |c: u32| nodes[c as usize].aabb.half_area();
            let open = (0..k)
                .filter(|&j| nodes[kids[j] as usize].prim_count == 0)
                .max_by(|&a, &b| area(kids[a]).total_cmp(&area(kids[b])));
            let Some(j) = open else { break };
            let f = nodes[kids[j] as usize].first_index;
            (kids[j], kids[k]) = (f, f + 1);
            k += 1;
        }
        let mut node = EMPTY_NODE;
        for (slot, &c) in kids[..k].iter().enumerate() {
            let b = &nodes[c as usize].aabb;
            for axis in 0..3 {
                node.lo[axis][slot] = b.min[axis];
                node.hi[axis][slot] = b.max[axis];
            }
        }
        (node, Kids { kids, len: k })
    }

    /// Bytes held (allocated, not only used).
    pub fn heap_bytes(&self) -> u64 {
        fn of<T>(v: &Vec<T>) -> u64 {
            (v.capacity() * size_of::<T>()) as u64
        }
        of(&self.nodes) + of(&self.blocks) + of(&self.balls) + of(&self.leaves) + of(&self.others)
    }

    /// Nodes and triangle blocks (for reports).
    pub fn counts(&self) -> (usize, usize) {
        (self.nodes.len(), self.blocks.len())
    }

    /// The nearest hit with `t` in `(t_min, t_max)` along `o + t d`, with
    /// the kernels built for `level` (the portable ones where this CPU
    /// does not run it). `other(p, t_max)` tests primitive `p` of a
    /// leaf's list, giving its first hit in `(t_min, t_max)`.
    pub fn closest(
        &self,
        level: Level,
        (o, d): (Vec3, Vec3),
        (t_min, t_max): (f32, f32),
        other: &mut dyn FnMut(u32, f32) -> Option<(f32, Vec2)>,
    ) -> Option<Found> {
        if self.root == EMPTY {
            return None;
        }
        #[cfg(target_arch = "x86_64")]
        {
            if level == Level::Avx512 && level.runs() {
                // SAFETY: this CPU runs AVX-512 F, VL, DQ, BW, AVX2 and FMA.
                return unsafe { self.closest_avx512(o, d, t_min, t_max, other) };
            }
            if level >= Level::Avx2 && Level::Avx2.runs() {
                // SAFETY: this CPU runs AVX2 and FMA.
                return unsafe { self.closest_avx2(o, d, t_min, t_max, other) };
            }
        }
        let _ = level;
        self.closest_body(o, d, t_min, t_max, other)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    unsafe fn closest_avx512(
        &self,
        o: Vec3,
        d: Vec3,
        t_min: f32,
        t_max: f32,
        other: &mut dyn FnMut(u32, f32) -> Option<(f32, Vec2)>,
    ) -> Option<Found> {
        self.closest_body(o, d, t_min, t_max, other)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn closest_avx2(
        &self,
        o: Vec3,
        d: Vec3,
        t_min: f32,
        t_max: f32,
        other: &mut dyn FnMut(u32, f32) -> Option<(f32, Vec2)>,
    ) -> Option<Found> {
        self.closest_body(o, d, t_min, t_max, other)
    }

    #[inline(always)]
    fn closest_body(
        &self,
        o: Vec3,
        d: Vec3,
        t_min: f32,
        t_max: f32,
        other: &mut dyn FnMut(u32, f32) -> Option<(f32, Vec2)>,
    ) -> Option<Found> {
        let ray = Ray::new(o, d);
        // Left uninitialised: a ray reads only the entries it wrote, and
        // zeroing a stack per ray costs more than most traversals.
        let mut local = [const { MaybeUninit::<(u32, f32)>::uninit() }; 256];
        let mut heap = Vec::new();
        let stack: &mut [MaybeUninit<(u32, f32)>] = if self.stack <= local.len() {
            &mut local
        } else {
            heap.resize(self.stack, MaybeUninit::uninit());
            &mut heap
        };
        stack[0] = MaybeUninit::new((self.root, t_min));
        let mut top = 1;
        let mut best: Option<Found> = None;
        let mut far = t_max;
        while top > 0 {
            top -= 1;
            // SAFETY: entries below `top` were all written.
            let (reference, near) = unsafe { stack[top].assume_init() };
            if near >= far {
                continue;
            }
            if reference & LEAF == 0 {
                let node = &self.nodes[reference as usize];
                let (tn, mut mask) = enter(node, &ray, t_min, far);
                // The children hit, farthest first on the stack so that
                // the nearest is taken next.
                let base = top;
                while mask != 0 {
                    let slot = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let entry = (node.child[slot], tn[slot]);
                    let mut j = top;
                    // SAFETY: entries from `base` below `top` were written.
                    while j > base && unsafe { stack[j - 1].assume_init() }.1 < entry.1 {
                        stack[j] = stack[j - 1];
                        j -= 1;
                    }
                    stack[j] = MaybeUninit::new(entry);
                    top += 1;
                }
                continue;
            }
            self.leaf(reference, &ray, t_min, (&mut far, &mut best), &mut *other);
        }
        best
    }

    /// Tests `ray` against every primitive of leaf `reference` nearer
    /// than `far`, which the nearest hit found shortens.
    #[inline(always)]
    fn leaf(
        &self,
        reference: u32,
        ray: &Ray,
        t_min: f32,
        (far, best): (&mut f32, &mut Option<Found>),
        other: &mut dyn FnMut(u32, f32) -> Option<(f32, Vec2)>,
    ) {
        let leaf = self.leaves[(reference & !LEAF) as usize];
        let blocks = &self.blocks[leaf.block as usize..(leaf.block + leaf.blocks) as usize];
        for block in blocks {
            if let Some((lane, t, u, v)) = cross(block, ray, t_min, *far) {
                *far = t;
                let corner = |e: &[[f32; WIDTH]; 3]| Vec3::new(e[0][lane], e[1][lane], e[2][lane]);
                let a = corner(&block.a);
                *best = Some(Found {
                    prim: block.prim[lane],
                    t,
                    bary: Vec2::new(u, v),
                    facing: Some((corner(&block.b) - a).cross(corner(&block.c) - a)),
                });
            }
        }
        let balls = &self.balls[leaf.ball as usize..(leaf.ball + leaf.balls) as usize];
        for ball in balls {
            if let Some((lane, t)) = meet(ball, ray, t_min, *far) {
                *far = t;
                *best = Some(Found {
                    prim: ball.prim[lane],
                    t,
                    bary: Vec2::ZERO,
                    facing: None,
                });
            }
        }
        let others = &self.others[leaf.other as usize..(leaf.other + leaf.others) as usize];
        for &p in others {
            if let Some((t, bary)) = other(p, *far) {
                if t < *far {
                    *far = t;
                    *best = Some(Found {
                        prim: p,
                        t,
                        bary,
                        facing: None,
                    });
                }
            }
        }
    }

    /// The nearest hits of up to WIDTH rays traced together, each with
    /// `t` in `(t_min, t_max)`: what [`Wide::closest`] finds for each
    /// (the same primitive but where two are hit at the very same
    /// distance). `other(ray, p, t_max)` tests primitive `p` of a leaf's
    /// list for ray `ray`.
    ///
    /// Rays whose directions agree in sign on every axis, as a few
    /// neighbouring pixels' camera rays do, go down the tree together:
    /// an inner node's boxes are tested once for all of them, by interval
    /// arithmetic over their origins and inverse directions (Boulos et
    /// al., "Geometric and Arithmetic Culling Methods for Entire Ray
    /// Packets", 2006), with the operations the single ray's test uses, so
    /// the bound holds to the bit; a leaf's box is then tested for each
    /// ray, and each tests the leaf only where it enters it. Other rays
    /// go one by one.
    pub fn closest_packet(
        &self,
        level: Level,
        rays: &[(Vec3, Vec3)],
        (t_min, t_max): (f32, f32),
        other: &mut dyn FnMut(usize, u32, f32) -> Option<(f32, Vec2)>,
    ) -> [Option<Found>; WIDTH] {
        assert!(rays.len() <= WIDTH, "a packet holds at most {WIDTH} rays");
        if self.root == EMPTY || rays.is_empty() {
            return [None; WIDTH];
        }
        #[cfg(target_arch = "x86_64")]
        {
            if level == Level::Avx512 && level.runs() {
                // SAFETY: this CPU runs AVX-512 F, VL, DQ, BW, AVX2 and FMA.
                return unsafe { self.packet_avx512(rays, t_min, t_max, other) };
            }
            if level >= Level::Avx2 && Level::Avx2.runs() {
                // SAFETY: this CPU runs AVX2 and FMA.
                return unsafe { self.packet_avx2(rays, t_min, t_max, other) };
            }
        }
        let _ = level;
        self.packet_body(rays, t_min, t_max, other)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    unsafe fn packet_avx512(
        &self,
        rays: &[(Vec3, Vec3)],
        t_min: f32,
        t_max: f32,
        other: &mut dyn FnMut(usize, u32, f32) -> Option<(f32, Vec2)>,
    ) -> [Option<Found>; WIDTH] {
        self.packet_body(rays, t_min, t_max, other)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn packet_avx2(
        &self,
        rays: &[(Vec3, Vec3)],
        t_min: f32,
        t_max: f32,
        other: &mut dyn FnMut(usize, u32, f32) -> Option<(f32, Vec2)>,
    ) -> [Option<Found>; WIDTH] {
        self.packet_body(rays, t_min, t_max, other)
    }

    #[inline(always)]
    fn packet_body(
        &self,
        rays: &[(Vec3, Vec3)],
        t_min: f32,
        t_max: f32,
        other: &mut dyn FnMut(usize, u32, f32) -> Option<(f32, Vec2)>,
    ) -> [Option<Found>; WIDTH] {
        let n = rays.len();
        // Lanes past the last ray repeat it: they widen no interval and
        // are never active.
        let one: [Ray; WIDTH] = std::array::from_fn(|i| {
            let (o, d) = rays[i.min(n - 1)];
            Ray::new(o, d)
        });
        let mut best = [None; WIDTH];
        let neg = one[0].neg;
        if one.iter().any(|r| r.neg != neg) {
            for (i, ray) in one.iter().enumerate().take(n) {
                best[i] =
                    self.closest_body(ray.o, ray.d, t_min, t_max, &mut |p, far| other(i, p, far));
            }
            return best;
        }
        // Each axis's origins and inverse directions, lane by lane and as
        // intervals.
        let lanes =
            |f: &dyn Fn(&Ray) -> f32| -> [f32; WIDTH] { std::array::from_fn(|i| f(&one[i])) };
        let o: [[f32; WIDTH]; 3] = std::array::from_fn(|a| lanes(&|r| r.o[a]));
        let inv: [[f32; WIDTH]; 3] = std::array::from_fn(|a| lanes(&|r| r.inv[a]));
        let span = |v: &[f32; WIDTH]| {
            v.iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &x| {
                    (min(lo, x), max(hi, x))
                })
        };
        let o_span: Spans = std::array::from_fn(|a| span(&o[a]));
        let inv_span: Spans = std::array::from_fn(|a| span(&inv[a]));
        let all = (1u32 << n) - 1;
        let mut far = [t_max; WIDTH];
        let mut local = [const { MaybeUninit::<(u32, f32, u32)>::uninit() }; 256];
        let mut heap = Vec::new();
        let stack: &mut [MaybeUninit<(u32, f32, u32)>] = if self.stack <= local.len() {
            &mut local
        } else {
            heap.resize(self.stack, MaybeUninit::uninit());
            &mut heap
        };
        stack[0] = MaybeUninit::new((self.root, t_min, all));
        let mut top = 1;
        while top > 0 {
            top -= 1;
            // SAFETY: entries below `top` were all written.
            let (reference, near, mask) = unsafe { stack[top].assume_init() };
            // The farthest any of the entry's rays still looks.
            let mut reach = f32::NEG_INFINITY;
            for (i, &f) in far.iter().enumerate() {
                if mask & (1 << i) != 0 {
                    reach = max(reach, f);
                }
            }
            if near >= reach {
                continue;
            }
            if reference & LEAF != 0 {
                let mut left = mask;
                while left != 0 {
                    let i = left.trailing_zeros() as usize;
                    left &= left - 1;
                    if near < far[i] {
                        let mut each = |p: u32, f: f32| other(i, p, f);
                        self.leaf(
                            reference,
                            &one[i],
                            t_min,
                            (&mut far[i], &mut best[i]),
                            &mut each,
                        );
                    }
                }
                continue;
            }
            let node = &self.nodes[reference as usize];
            let (tn, mut slots) = enter_all(node, neg, (&o_span, &inv_span), t_min, reach);
            let base = top;
            while slots != 0 {
                let slot = slots.trailing_zeros() as usize;
                slots &= slots - 1;
                let child = node.child[slot];
                let rays_in = if child & LEAF != 0 {
                    mask & enter_each(node, slot, neg, (&o, &inv), t_min, &far)
                } else {
                    mask
                };
                if rays_in == 0 {
                    continue;
                }
                let entry = (child, tn[slot], rays_in);
                let mut j = top;
                // SAFETY: entries from `base` below `top` were written.
                while j > base && unsafe { stack[j - 1].assume_init() }.1 < entry.1 {
                    stack[j] = stack[j - 1];
                    j -= 1;
                }
                stack[j] = MaybeUninit::new(entry);
                top += 1;
            }
        }
        best
    }
}

/// A packet's least and greatest value of something on each axis.
type Spans = [(f32, f32); 3];

/// A lower bound of where any of a packet's rays enters each of `node`'s
/// boxes, within `(t_min, t_max)`, and a bit per box one of them may
/// enter. The rays' directions share the signs `neg`; `spans` are their
/// origins' and inverse directions' intervals on each axis. Each bound is
/// the single ray's operations on an interval's end, chosen by sign:
/// rounding is monotonic, so no ray's own distance passes it.
#[inline(always)]
fn enter_all(
    node: &Node,
    neg: [bool; 3],
    (o, inv): (&Spans, &Spans),
    t_min: f32,
    t_max: f32,
) -> ([f32; WIDTH], u32) {
    let mut near = [t_min; WIDTH];
    let mut far = [t_max; WIDTH];
    for axis in 0..3 {
        let ((o_lo, o_hi), (i_lo, i_hi)) = (o[axis], inv[axis]);
        let (lo, hi) = (&node.lo[axis], &node.hi[axis]);
        for k in 0..WIDTH {
            // The least entry and the greatest exit over the packet.
            let (n, f) = if neg[axis] {
                let x = hi[k] - o_lo;
                let y = lo[k] - o_hi;
                (
                    if x >= 0.0 { x * i_lo } else { x * i_hi },
                    if y <= 0.0 { y * i_lo } else { y * i_hi },
                )
            } else {
                let x = lo[k] - o_hi;
                let y = hi[k] - o_lo;
                (
                    if x >= 0.0 { x * i_lo } else { x * i_hi },
                    if y >= 0.0 { y * i_hi } else { y * i_lo },
                )
            };
            near[k] = max(near[k], n);
            far[k] = min(far[k], f);
        }
    }
    let mut mask = 0;
    for k in 0..WIDTH {
        mask |= u32::from(near[k] <= far[k] * ROBUST) << k;
    }
    (near, mask)
}

/// Which of a packet's rays enter `node`'s box `slot` before their own
/// `far`: [`enter`]'s test for each ray, lane by lane.
#[inline(always)]
fn enter_each(
    node: &Node,
    slot: usize,
    neg: [bool; 3],
    (o, inv): (&[[f32; WIDTH]; 3], &[[f32; WIDTH]; 3]),
    t_min: f32,
    far: &[f32; WIDTH],
) -> u32 {
    let plane = |axis: usize| {
        let (lo, hi) = (node.lo[axis][slot], node.hi[axis][slot]);
        if neg[axis] {
            (hi, lo)
        } else {
            (lo, hi)
        }
    };
    let ((nx, fx), (ny, fy), (nz, fz)) = (plane(0), plane(1), plane(2));
    let mut mask = 0;
    for i in 0..WIDTH {
        let tx = ((nx - o[0][i]) * inv[0][i], (fx - o[0][i]) * inv[0][i]);
        let ty = ((ny - o[1][i]) * inv[1][i], (fy - o[1][i]) * inv[1][i]);
        let tz = ((nz - o[2][i]) * inv[2][i], (fz - o[2][i]) * inv[2][i]);
        let near = max(max(tx.0, ty.0), max(tz.0, t_min));
        let exit = min(min(tx.1, ty.1), min(tz.1, far[i])) * ROBUST;
        mask |= u32::from(near <= exit) << i;
    }
    mask
}

/// What one part of a wide tree holds, counted before it is made.
#[derive(Clone, Copy, Default)]
struct Sizes {
    nodes: usize,
    blocks: usize,
    balls: usize,
    leaves: usize,
    others: usize,
    /// Levels of wide nodes to its deepest leaf.
    deepest: usize,
}

impl Sizes {
    /// The same numbers of every kind of element (not the depth).
    fn same_counts(&self, o: &Sizes) -> bool {
        (
            self.nodes,
            self.blocks,
            self.balls,
            self.leaves,
            self.others,
        ) == (o.nodes, o.blocks, o.balls, o.leaves, o.others)
    }

    fn plus(self, o: &Sizes) -> Sizes {
        Sizes {
            nodes: self.nodes + o.nodes,
            blocks: self.blocks + o.blocks,
            balls: self.balls + o.balls,
            leaves: self.leaves + o.leaves,
            others: self.others + o.others,
            deepest: self.deepest.max(o.deepest),
        }
    }

    /// The wide tree of the binary subtree at `i`, as [`Out::part`] will
    /// make it.
    fn of(bvh: &Bvh2, i: u32, prims: &impl Primitives) -> Sizes {
        let mut size = Sizes::default();
        let mut work = vec![(i, 1usize)];
        let mut pending = Vec::new();
        while let Some((i, level)) = work.pop() {
            size.deepest = size.deepest.max(level);
            if bvh.nodes[i as usize].prim_count == 0 {
                size.nodes += 1;
                work.extend(Wide::opened(bvh, i).1.iter().map(|&c| (c, level + 1)));
                continue;
            }
            size.leaves += 1;
            let (mut triangles, mut spheres) = (0usize, 0usize);
            leaf_primitives(bvh, i, &mut pending, |p| match prims.kind(p) {
                Kind::Triangle => triangles += 1,
                Kind::Sphere => spheres += 1,
                Kind::Other => size.others += 1,
            });
            size.blocks += triangles.div_ceil(WIDTH);
            size.balls += spheres.div_ceil(WIDTH);
        }
        size
    }
}

/// Every primitive under binary node `i`, in order.
fn leaf_primitives(bvh: &Bvh2, i: u32, pending: &mut Vec<u32>, mut f: impl FnMut(u32)) {
    pending.clear();
    pending.push(i);
    while let Some(n) = pending.pop() {
        let n = &bvh.nodes[n as usize];
        if n.prim_count == 0 {
            pending.extend([n.first_index + 1, n.first_index]);
            continue;
        }
        let first = n.first_index as usize;
        for &p in &bvh.primitive_indices[first..first + n.prim_count as usize] {
            f(p);
        }
    }
}

/// The binary nodes a wide node's slots stand for.
struct Kids {
    kids: [u32; WIDTH],
    len: usize,
}

impl std::ops::Deref for Kids {
    type Target = [u32];

    fn deref(&self) -> &[u32] {
        &self.kids[..self.len]
    }
}

/// One part's slices of a wide tree's arrays, where they start in the
/// whole, and how far each is filled.
/// Its slices start unwritten; each element is written once.
struct Out<'a> {
    nodes: &'a mut [MaybeUninit<Node>],
    blocks: &'a mut [MaybeUninit<Block>],
    balls: &'a mut [MaybeUninit<Ball>],
    leaves: &'a mut [MaybeUninit<Leaf>],
    others: &'a mut [MaybeUninit<u32>],
    base: Sizes,
    filled: Sizes,
}

impl<'a> Out<'a> {
    fn new(
        nodes: &'a mut [MaybeUninit<Node>],
        (blocks, balls): (&'a mut [MaybeUninit<Block>], &'a mut [MaybeUninit<Ball>]),
        leaves: &'a mut [MaybeUninit<Leaf>],
        others: &'a mut [MaybeUninit<u32>],
        base: Sizes,
    ) -> Self {
        Out {
            nodes,
            blocks,
            balls,
            leaves,
            others,
            base,
            filled: Sizes::default(),
        }
    }

    /// The wide tree of the binary subtree at `i`, written into this
    /// part's slices (which [`Sizes::of`] measured with the same
    /// `prims`); its root's reference.
    fn part(&mut self, bvh: &Bvh2, i: u32, prims: &impl Primitives) -> u32 {
        let mut root = EMPTY;
        // (binary node, local wide node and slot that refer to it).
        let mut work = vec![(i, None::<(usize, usize)>)];
        let mut pending = Vec::new();
        while let Some((i, parent)) = work.pop() {
            let reference = if bvh.nodes[i as usize].prim_count > 0 {
                self.leaf(bvh, i, prims, &mut pending)
            } else {
                let at = self.filled.nodes;
                self.filled.nodes += 1;
                let (node, kids) = Wide::opened(bvh, i);
                for (slot, &c) in kids.iter().enumerate() {
                    work.push((c, Some((at, slot))));
                }
                self.nodes[at].write(node);
                (self.base.nodes + at) as u32
            };
            match parent {
                Some((node, slot)) => {
                    // SAFETY: a parent is written before its children are
                    // taken from `work`.
                    unsafe { self.nodes[node].assume_init_mut() }.child[slot] = reference
                }
                None => root = reference,
            }
        }
        root
    }

    /// A leaf of every primitive under binary node `i`; its reference.
    /// Blocks are filled on the stack and written whole, their unused
    /// lanes empty.
    fn leaf(&mut self, bvh: &Bvh2, i: u32, prims: &impl Primitives, pending: &mut Vec<u32>) -> u32 {
        let first = self.filled;
        let (mut block, mut lane) = (EMPTY_BLOCK, 0);
        let (mut ball, mut ball_lane) = (EMPTY_BALL, 0);
        let (blocks, balls) = (&mut *self.blocks, &mut *self.balls);
        let (others, filled) = (&mut *self.others, &mut self.filled);
        leaf_primitives(bvh, i, pending, |p| match prims.kind(p) {
            Kind::Other => {
                others[filled.others].write(p);
                filled.others += 1;
            }
            Kind::Triangle => {
                let [a, b, c] = prims.triangle(p);
                for axis in 0..3 {
                    block.a[axis][lane] = a[axis];
                    block.b[axis][lane] = b[axis];
                    block.c[axis][lane] = c[axis];
                }
                block.prim[lane] = p;
                lane += 1;
                if lane == WIDTH {
                    blocks[filled.blocks].write(block);
                    filled.blocks += 1;
                    (block, lane) = (EMPTY_BLOCK, 0);
                }
            }
            Kind::Sphere => {
                let (c, r) = prims.sphere(p);
                for axis in 0..3 {
                    ball.c[axis][ball_lane] = c[axis];
                }
                ball.r[ball_lane] = r;
                ball.prim[ball_lane] = p;
                ball_lane += 1;
                if ball_lane == WIDTH {
                    balls[filled.balls].write(ball);
                    filled.balls += 1;
                    (ball, ball_lane) = (EMPTY_BALL, 0);
                }
            }
        });
        if lane > 0 {
            self.blocks[self.filled.blocks].write(block);
            self.filled.blocks += 1;
        }
        if ball_lane > 0 {
            self.balls[self.filled.balls].write(ball);
            self.filled.balls += 1;
        }
        let at = self.filled.leaves;
        let (now, base) = (self.filled, self.base);
        self.leaves[at].write(Leaf {
            block: (base.blocks + first.blocks) as u32,
            blocks: (now.blocks - first.blocks) as u32,
            ball: (base.balls + first.balls) as u32,
            balls: (now.balls - first.balls) as u32,
            other: (base.others + first.others) as u32,
            others: (now.others - first.others) as u32,
        });
        self.filled.leaves += 1;
        LEAF | (self.base.leaves + at) as u32
    }
}

/// The entry distance of `ray` into each of `node`'s boxes within
/// `(t_min, t_max)`, and a bit per box it enters.
#[inline(always)]
fn enter(node: &Node, ray: &Ray, t_min: f32, t_max: f32) -> ([f32; WIDTH], u32) {
    let planes = |axis: usize| {
        if ray.neg[axis] {
            (&node.hi[axis], &node.lo[axis])
        } else {
            (&node.lo[axis], &node.hi[axis])
        }
    };
    let ((nx, fx), (ny, fy), (nz, fz)) = (planes(0), planes(1), planes(2));
    let (o, inv) = (ray.o, ray.inv);
    let mut near = [0f32; WIDTH];
    let mut far = [0f32; WIDTH];
    for i in 0..WIDTH {
        let tx = ((nx[i] - o.x) * inv[0], (fx[i] - o.x) * inv[0]);
        let ty = ((ny[i] - o.y) * inv[1], (fy[i] - o.y) * inv[1]);
        let tz = ((nz[i] - o.z) * inv[2], (fz[i] - o.z) * inv[2]);
        near[i] = max(max(tx.0, ty.0), max(tz.0, t_min));
        far[i] = min(min(tx.1, ty.1), min(tz.1, t_max)) * ROBUST;
    }
    let mut mask = 0;
    for i in 0..WIDTH {
        mask |= u32::from(near[i] <= far[i]) << i;
    }
    (near, mask)
}

/// The nearest of `ball`'s spheres `ray` meets within `(t_min, t_max)`:
/// its lane and distance (the far side from inside). The arithmetic is
/// intersect.rs's `sphere`, operation for operation.
#[inline(always)]
fn meet(ball: &Ball, ray: &Ray, t_min: f32, t_max: f32) -> Option<(usize, f32)> {
    let (o, d) = (ray.o, ray.d);
    let a = (d.x * d.x) + (d.y * d.y) + (d.z * d.z);
    if a == 0.0 {
        return None;
    }
    let mut ts = [0f32; WIDTH];
    for (i, lane) in ts.iter_mut().enumerate() {
        let ox = o.x - ball.c[0][i];
        let oy = o.y - ball.c[1][i];
        let oz = o.z - ball.c[2][i];
        let b = (ox * d.x) + (oy * d.y) + (oz * d.z);
        let f = b / a;
        let (px, py, pz) = (ox - d.x * f, oy - d.y * f, oz - d.z * f);
        let r = ball.r[i];
        let disc = r * r - ((px * px) + (py * py) + (pz * pz));
        let h = (a * disc).sqrt();
        let near = (-b - h) / a;
        let far = (-b + h) / a;
        let t = if near > t_min && near < t_max {
            near
        } else if far > t_min && far < t_max {
            far
        } else {
            f32::INFINITY
        };
        // An empty lane (radius -1) and a miss (disc < 0, h NaN) fail.
        *lane = if r >= 0.0 && disc >= 0.0 {
            t
        } else {
            f32::INFINITY
        };
    }
    let mut lane = WIDTH;
    let mut nearest = f32::INFINITY;
    for (i, &t) in ts.iter().enumerate() {
        if t < nearest {
            (lane, nearest) = (i, t);
        }
    }
    (lane < WIDTH).then_some((lane, nearest))
}

/// The nearest of `block`'s triangles `ray` crosses within `(t_min,
/// t_max)`: its lane, distance and barycentrics. The arithmetic is
/// intersect.rs's `sheared_triangle`, operation for operation, and so
/// are the negated comparisons (a NaN passes them there too).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
#[inline(always)]
fn cross(block: &Block, ray: &Ray, t_min: f32, t_max: f32) -> Option<(usize, f32, f32, f32)> {
    let o = ray.o;
    let [kx, ky, kz] = ray.shear.k;
    let [sx, sy, sz] = ray.shear.s;
    let (ox, oy, oz) = (o[kx], o[ky], o[kz]);
    // The corners' coordinates in the ray's frame, the ray's axis last.
    let (axs, ays, azs) = (&block.a[kx], &block.a[ky], &block.a[kz]);
    let (bxs, bys, bzs) = (&block.b[kx], &block.b[ky], &block.b[kz]);
    let (cxs, cys, czs) = (&block.c[kx], &block.c[ky], &block.c[kz]);
    let mut ts = [0f32; WIDTH];
    let mut us = [0f32; WIDTH];
    let mut vs = [0f32; WIDTH];
    for i in 0..WIDTH {
        let (az, bz, cz) = (azs[i] - oz, bzs[i] - oz, czs[i] - oz);
        let (ax, ay) = ((axs[i] - ox) - sx * az, (ays[i] - oy) - sy * az);
        let (bx, by) = ((bxs[i] - ox) - sx * bz, (bys[i] - oy) - sy * bz);
        let (cx, cy) = ((cxs[i] - ox) - sx * cz, (cys[i] - oy) - sy * cz);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let inside = !((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0));
        let det = u + v + w;
        let t = u * (sz * az) + v * (sz * bz) + w * (sz * cz);
        let inv = 1.0 / det;
        let t = t * inv;
        let ok = inside && det != 0.0 && det.abs() < f32::INFINITY && t > t_min && t < t_max;
        ts[i] = if ok { t } else { f32::INFINITY };
        (us[i], vs[i]) = (v * inv, w * inv);
    }
    let mut lane = WIDTH;
    let mut nearest = f32::INFINITY;
    for (i, &t) in ts.iter().enumerate() {
        if t < nearest {
            (lane, nearest) = (i, t);
        }
    }
    (lane < WIDTH).then(|| (lane, nearest, us[lane], vs[lane]))
}
