//! Surfaces of triangles, spheres, cones and curves as the renderers trace them: every
//! placed shape's primitives in one BVH, built once for a scene's shapes
//! and kept while frames bring the same ones, the nearest hit along a ray,
//! and its color under the world's light. The volume march stops at that
//! hit and composites over its color (cpu/march.rs), so one ray sees both.
//!
//! The CPU traverses a wide BVH (wide.rs) collapsed from a binned SAH
//! tree (binned.rs), its boxes and triangles tested eight at a time; the
//! GPU a binary tree from obvhs's PLOC builder, whose flat nodes (a box,
//! a first index, a count) go to a storage buffer as they are (packed.rs),
//! and whose traversal binary.rs also runs here, for tests and benchmarks.
//! Triangles are placed in world space once; spheres and cylinders are
//! tested in object space, so an instance's shear or uneven scale makes
//! the ellipsoid it should.

mod binary;
mod binned;
mod brdf;
mod intersect;
pub mod packed;
mod pages;
mod wide;

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::Boundable;
use rayon::prelude::*;

use super::frame::filled;
use super::hits::HitRecord;
use super::simd::Level;
use super::{RenderError, RenderSettings, SurfaceShading};
use crate::geometry::RayGen;
use crate::scene::{
    Attribute, ColorSource, Coverage, OpacitySource, PlacedShape, Primitives, Source,
    DEFAULT_ATTRIBUTE,
};
use binned::Item;
use brdf::reflected;
pub use brdf::MIN_ROUGHNESS;
use intersect::{cone, curve, sphere, tangent_cone, triangle, End};

/// The most rays [`ShapeSet::hits`] traces together.
pub const PACKET: usize = wide::WIDTH;
use wide::Wide;

/// The most translucent surfaces one ray composites; those behind them
/// are passed through.
pub const MAX_TRANSLUCENT: u32 = 8;

/// Surfaces a ray looks for before it goes on through whatever is left
/// (translucent ones past MAX_TRANSLUCENT cost a traversal each).
pub const SURFACE_PASSES: u32 = 8 * MAX_TRANSLUCENT;

/// The scale of `ambientRadiance` under direct light: a radiance of 1
/// (the spec's default) adds a tenth of a surface's color, a fill that
/// leaves the lights' shading to be seen.
pub const AMBIENT_SCALE: f32 = 0.1;

/// One placed shape as traced: its world-space triangle corners, the maps
/// that spheres and normals need.
struct Traced {
    placed: PlacedShape,
    /// Triangle vertices in world space where the placement moves them
    /// (else empty: the shape's own are read, see [`Traced::world`]).
    moved: Vec<Vec3>,
    to_object: Mat4,
    /// Whether the shape is placed as it is (then rays need no map into
    /// object space: a sphere test is a tenth the work).
    identity: bool,
    /// Object-space normals to world space (the inverse transpose).
    normal_to_world: Mat3,
    /// Whether its opacity varies over it and can hide parts of it: then
    /// a traversal looks at each hit's.
    cuts: bool,
}

impl Traced {
    /// Triangle vertices in world space (none for other shapes).
    fn world(&self) -> &[Vec3] {
        match &self.placed.shape.primitives {
            Primitives::Triangles { positions, .. } if self.identity => positions,
            _ => &self.moved,
        }
    }

    fn point_to_object(&self, p: Vec3) -> Vec3 {
        if self.identity {
            p
        } else {
            self.to_object.transform_point3(p)
        }
    }

    fn ray_to_object(&self, o: Vec3, d: Vec3) -> (Vec3, Vec3) {
        if self.identity {
            (o, d)
        } else {
            (
                self.to_object.transform_point3(o),
                self.to_object.transform_vector3(d),
            )
        }
    }
}

/// The wide tree's view of a shape set's primitives: triangles and
/// spheres are tested in blocks, in world space, unless their opacity
/// can hide parts of them (then each hit's coverage is looked at) or, for
/// spheres, an instance places them (then the ray is mapped into object
/// space).
struct Kinds<'a> {
    prims: &'a [Prim],
    traced: &'a [Traced],
    /// Per traced shape, its kind and, for triangles, the world-space
    /// positions and the index triples: found once, not per primitive.
    shapes: Vec<ShapeKind<'a>>,
}

/// A traced shape's kind, and its triangles' world positions and index
/// triples (empty unless it is tested as triangles).
type ShapeKind<'a> = (wide::Kind, &'a [Vec3], &'a [[u32; 3]]);

impl<'a> Kinds<'a> {
    fn new(prims: &'a [Prim], traced: &'a [Traced]) -> Self {
        let shapes = traced
            .iter()
            .map(|t| match &t.placed.shape.primitives {
                _ if t.cuts => (wide::Kind::Other, &[][..], &[][..]),
                Primitives::Triangles { triangles, .. } => {
                    (wide::Kind::Triangle, t.world(), &triangles[..])
                }
                Primitives::Spheres { .. } if t.identity => (wide::Kind::Sphere, &[][..], &[][..]),
                _ => (wide::Kind::Other, &[][..], &[][..]),
            })
            .collect();
        Self {
            prims,
            traced,
            shapes,
        }
    }
}

impl wide::Primitives for Kinds<'_> {
    fn kind(&self, p: u32) -> wide::Kind {
        self.shapes[self.prims[p as usize].shape as usize].0
    }

    fn triangle(&self, p: u32) -> [Vec3; 3] {
        let prim = self.prims[p as usize];
        let (_, world, triangles) = self.shapes[prim.shape as usize];
        triangles[prim.index as usize].map(|v| world[v as usize])
    }

    fn sphere(&self, p: u32) -> (Vec3, f32) {
        let prim = self.prims[p as usize];
        match &self.traced[prim.shape as usize].placed.shape.primitives {
            Primitives::Spheres {
                positions,
                radii,
                spheres,
            } => {
                let v = spheres[prim.index as usize] as usize;
                (positions[v], radii[v])
            }
            _ => unreachable!("kind says which primitives are spheres"),
        }
    }
}

/// A BVH primitive: the kept primitive `index` of placed shape `shape`.
#[derive(Clone, Copy)]
struct Prim {
    shape: u32,
    index: u32,
}

struct Boxed(Aabb);

impl Boundable for Boxed {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// The nearest surface along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// Placed shape, and kept primitive within it.
    pub shape: u32,
    pub index: u32,
    /// Weights of a triangle's second and third corner.
    pub bary: Vec2,
    /// World space, unit length, facing the ray.
    pub normal: Vec3,
}

/// How a shape set's BVH is kept.
enum Tree {
    /// Binary, as obvhs builds it: what the GPU traverses.
    Binary(Bvh2),
    /// Eight children to a node, triangles in blocks: what the CPU
    /// traverses.
    Wide(Wide),
}

/// A scene's shapes, ready to trace.
pub struct ShapeSet {
    traced: Vec<Traced>,
    prims: Vec<Prim>,
    tree: Tree,
}

impl std::fmt::Debug for ShapeSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShapeSet")
            .field("shapes", &self.traced.len())
            .field("primitives", &self.prims.len())
            .field(
                "nodes",
                &match &self.tree {
                    Tree::Binary(bvh) => bvh.nodes.len(),
                    Tree::Wide(wide) => wide.counts().0,
                },
            )
            .finish()
    }
}

/// An empty vector with room for `n`, in huge pages where it is large,
/// or an error if the memory cannot be had.
fn reserved<T>(n: usize, what: &str) -> Result<Vec<T>, RenderError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| RenderError::OutOfMemory {
            bytes: (n as u64).saturating_mul(size_of::<T>() as u64),
            what: what.into(),
        })?;
    pages::ask_huge(v.spare_capacity_mut());
    Ok(v)
}

impl ShapeSet {
    /// The wide BVH over every kept primitive of `shapes`, as the CPU
    /// traverses it.
    pub fn build(shapes: &[PlacedShape]) -> Result<Self, RenderError> {
        Self::build_as(shapes, true)
    }

    /// The binary BVH over every kept primitive of `shapes`, as the GPU
    /// traverses it ([`ShapeSet::pack`]).
    pub fn build_binary(shapes: &[PlacedShape]) -> Result<Self, RenderError> {
        Self::build_as(shapes, false)
    }

    fn build_as(shapes: &[PlacedShape], wide: bool) -> Result<Self, RenderError> {
        let total: usize = shapes.iter().map(|s| s.shape.len()).sum();
        let mut prims: Vec<Prim> = reserved(total, "the BVH's primitives")?;
        let mut boxes: Vec<Item> = reserved(total, "the BVH's boxes")?;
        let mut traced = Vec::with_capacity(shapes.len());
        for (s, placed) in shapes.iter().enumerate() {
            let m = placed.transform;
            let fixed = placed.material.fixed_coverage();
            let hidden = fixed == Some(Coverage::Hidden);
            let to_object = m.inverse();
            let normal_to_world = Mat3::from_mat4(to_object).transpose();
            let shape = &placed.shape;
            let identity = m == Mat4::IDENTITY;
            let mut moved = Vec::new();
            match &shape.primitives {
                Primitives::Triangles {
                    positions,
                    triangles,
                    ..
                } => {
                    if !identity {
                        moved = filled(
                            positions.len(),
                            Vec3::ZERO,
                            "the triangles' world positions",
                        )?;
                        moved
                            .par_iter_mut()
                            .zip(positions.par_iter())
                            .for_each(|(w, p)| *w = m.transform_point3(*p));
                    }
                    let world: &[Vec3] = if identity { positions } else { &moved };
                    let base = boxes.len() as u32;
                    boxes.par_extend(triangles.par_iter().enumerate().map(|(i, tri)| {
                        let [a, b, c] = tri.map(|v| world[v as usize]);
                        Item {
                            lo: a.min(b).min(c),
                            index: base + i as u32,
                            hi: a.max(b).max(c),
                        }
                    }));
                }
                Primitives::Spheres {
                    positions,
                    radii,
                    spheres,
                } => {
                    for &v in spheres {
                        let (c, r) = (positions[v as usize], radii[v as usize]);
                        let (lo, hi) = crate::scene::transformed_box(m, (c - r, c + r));
                        boxes.push(Item {
                            lo,
                            index: boxes.len() as u32,
                            hi,
                        });
                    }
                }
                Primitives::Cones { .. } | Primitives::Curves { .. } => {
                    for index in 0..shape.len() {
                        let [(p, rp), (q, rq)] = Self::ends(&shape.primitives, index);
                        let r = rp.max(rq);
                        let object = (p.min(q) - r, p.max(q) + r);
                        let (lo, hi) = crate::scene::transformed_box(m, object);
                        boxes.push(Item {
                            lo,
                            index: boxes.len() as u32,
                            hi,
                        });
                    }
                }
            }
            if hidden {
                // Kept in `traced`, so that shape numbers stay the
                // scene's, but never hit.
                boxes.truncate(prims.len());
            } else {
                prims.extend((0..shape.len() as u32).map(|index| Prim {
                    shape: s as u32,
                    index,
                }));
            }
            traced.push(Traced {
                placed: placed.clone(),
                moved,
                to_object,
                identity,
                normal_to_world,
                cuts: fixed.is_none(),
            });
        }
        let tree = if boxes.is_empty() {
            Tree::Binary(Bvh2::default())
        } else if wide {
            let n = boxes.len();
            let bvh = binned::build(&mut boxes, wide::LEAF_MAX as usize).ok_or_else(|| {
                RenderError::OutOfMemory {
                    bytes: (2 * n * size_of::<obvhs::bvh2::node::Bvh2Node>()) as u64,
                    what: "the BVH's nodes".into(),
                }
            })?;
            drop(boxes);
            let prims = Kinds::new(&prims, &traced);
            Tree::Wide(Wide::collapse(&bvh, &prims))
        } else {
            let boxed: Vec<Boxed> = boxes
                .iter()
                .map(|b| Boxed(Aabb::new(b.lo.into(), b.hi.into())))
                .collect();
            drop(boxes);
            let mut took = std::time::Duration::ZERO;
            let params = obvhs::BvhBuildParams::fast_build();
            Tree::Binary(obvhs::bvh2::builder::build_bvh2(&boxed, params, &mut took))
        };
        Ok(Self {
            traced,
            prims,
            tree,
        })
    }

    /// Bytes the traced form holds beside the shapes themselves: world
    /// positions, the primitive list and the BVH (allocated, not only
    /// used).
    pub fn heap_bytes(&self) -> u64 {
        fn of<T>(v: &Vec<T>) -> u64 {
            (v.capacity() * size_of::<T>()) as u64
        }
        let world: u64 = self.traced.iter().map(|t| of(&t.moved)).sum();
        let tree = match &self.tree {
            Tree::Binary(bvh) => {
                of(&bvh.nodes)
                    + of(&bvh.primitive_indices)
                    + of(&bvh.primitive_indices_freelist)
                    + of(&bvh.primitives_to_nodes)
                    + of(&bvh.parents)
            }
            Tree::Wide(wide) => wide.heap_bytes(),
        };
        world + of(&self.prims) + tree
    }

    /// Primitives traced.
    pub fn len(&self) -> usize {
        self.prims.len()
    }

    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }

    /// The nearest hit with `t` in `(t_min, t_max)` along `o + t d`.
    pub fn hit(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        self.hit_on(Level::chosen(), o, d, t_min, t_max)
    }

    /// [`ShapeSet::hit`] with the wide BVH's kernels built for `level`.
    pub fn hit_on(&self, level: Level, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        if self.prims.is_empty() || t_max.partial_cmp(&t_min) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let (prim, t, bary, facing) = match &self.tree {
            Tree::Wide(wide) => {
                let mut other =
                    |p: u32, far: f32| self.shown(self.prims[p as usize], o, d, t_min, far);
                let found = wide.closest(level, (o, d), (t_min, t_max), &mut other)?;
                let prim = self.prims[found.prim as usize];
                (prim, found.t, found.bary, found.facing)
            }
            Tree::Binary(bvh) => {
                let indices = &bvh.primitive_indices;
                let prim_at = |j: u32| self.prims[indices[j as usize] as usize];
                let (j, t, bary) = binary::closest(
                    bvh,
                    (o, d),
                    (t_min, t_max),
                    packed::TRAVERSAL_STACK as usize,
                    |j, far| self.shown(prim_at(j), o, d, t_min, far),
                )?;
                (prim_at(j), t, bary, None)
            }
        };
        Some(self.finished(prim, (t, bary, facing), (o, d)))
    }

    /// The nearest hits of up to [`PACKET`] rays, each with `t` in
    /// `(t_min, t_max)`: [`ShapeSet::hit`]'s answers (but which of two
    /// primitives met at the very same distance), found together, which
    /// is faster for neighbouring camera rays.
    pub fn hits(&self, rays: &[(Vec3, Vec3)], t_min: f32, t_max: f32) -> [Option<Hit>; PACKET] {
        self.hits_on(Level::chosen(), rays, t_min, t_max)
    }

    /// [`ShapeSet::hits`] with the wide BVH's kernels built for `level`.
    pub fn hits_on(
        &self,
        level: Level,
        rays: &[(Vec3, Vec3)],
        t_min: f32,
        t_max: f32,
    ) -> [Option<Hit>; PACKET] {
        let mut out = [None; PACKET];
        let rays = &rays[..rays.len().min(PACKET)];
        let Tree::Wide(wide) = &self.tree else {
            for (hit, &(o, d)) in out.iter_mut().zip(rays) {
                *hit = self.hit_on(level, o, d, t_min, t_max);
            }
            return out;
        };
        if self.prims.is_empty() || t_max.partial_cmp(&t_min) != Some(std::cmp::Ordering::Greater) {
            return out;
        }
        let mut other = |i: usize, p: u32, far: f32| {
            let (o, d) = rays[i];
            self.shown(self.prims[p as usize], o, d, t_min, far)
        };
        let found = wide.closest_packet(level, rays, (t_min, t_max), &mut other);
        for ((hit, found), &ray) in out.iter_mut().zip(found).zip(rays) {
            *hit = found.map(|f| {
                let prim = self.prims[f.prim as usize];
                self.finished(prim, (f.t, f.bary, f.facing), ray)
            });
        }
        out
    }

    /// The first surface of each camera ray of `rays`' pixels `from..to`
    /// (a tile), row by row: [`ShapeSet::hits`] on blocks of 4 x 2
    /// pixels, whose rays are close enough to go down the tree together.
    pub fn camera_hits(
        &self,
        rays: &RayGen,
        (x0, y0): (usize, usize),
        (x1, y1): (usize, usize),
    ) -> Vec<Option<Hit>> {
        const BLOCK: (usize, usize) = (4, 2);
        let w = x1 - x0;
        let mut out = vec![None; w * (y1 - y0)];
        let mut pixels = Vec::with_capacity(PACKET);
        let mut ray = Vec::with_capacity(PACKET);
        for by in (y0..y1).step_by(BLOCK.1) {
            for bx in (x0..x1).step_by(BLOCK.0) {
                pixels.clear();
                ray.clear();
                for y in by..(by + BLOCK.1).min(y1) {
                    for x in bx..(bx + BLOCK.0).min(x1) {
                        pixels.push((y - y0) * w + (x - x0));
                        ray.push(rays.pixel_ray(x as u32, y as u32));
                    }
                }
                let hits = self.hits(&ray, rays.t_near, rays.t_far);
                for (&at, hit) in pixels.iter().zip(hits) {
                    out[at] = hit;
                }
            }
        }
        out
    }

    /// The hit of `prim` at `t` along `o + t d`, with its normal.
    fn finished(
        &self,
        prim: Prim,
        (t, bary, facing): (f32, Vec2, Option<Vec3>),
        (o, d): (Vec3, Vec3),
    ) -> Hit {
        let normal = self.normal(prim, o + d * t, bary, d, facing);
        Hit {
            t,
            shape: prim.shape,
            index: prim.index,
            bary,
            normal,
        }
    }

    /// Where `prim` is first hit and drawn in `(t_min, t_max)`: past the
    /// points its opacity hides.
    fn shown(&self, prim: Prim, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<(f32, Vec2)> {
        let found = self.distance(prim, o, d, t_min, t_max)?;
        if !self.traced[prim.shape as usize].cuts {
            return Some(found);
        }
        // A primitive meets a ray at most four times (a capped cone's
        // side twice and both discs).
        let mut from = found;
        for _ in 0..4 {
            let (t, bary) = from;
            let hit = Self::point_hit(prim, t, bary);
            if self.coverage(&hit) != Coverage::Hidden {
                return Some(from);
            }
            from = self.distance(prim, o, d, t, t_max)?;
        }
        None
    }

    /// A hit of `prim` at `t` as far as its attributes go (its normal
    /// unknown).
    fn point_hit(prim: Prim, t: f32, bary: Vec2) -> Hit {
        Hit {
            t,
            shape: prim.shape,
            index: prim.index,
            bary,
            normal: Vec3::ZERO,
        }
    }

    /// Where `prim` is hit in `(t_min, t_max)`, with its barycentrics.
    fn distance(
        &self,
        prim: Prim,
        o: Vec3,
        d: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, Vec2)> {
        let traced = &self.traced[prim.shape as usize];
        let t = match &traced.placed.shape.primitives {
            Primitives::Triangles { triangles, .. } => {
                let [a, b, c] = triangles[prim.index as usize].map(|v| traced.world()[v as usize]);
                return triangle(o, d, a, b, c).filter(|(t, _)| *t > t_min && *t < t_max);
            }
            Primitives::Spheres {
                positions,
                radii,
                spheres,
            } => {
                let v = spheres[prim.index as usize] as usize;
                let (oo, od) = traced.ray_to_object(o, d);
                sphere(oo, od, positions[v], radii[v], t_min, t_max)?
            }
            primitives @ (Primitives::Cones { .. } | Primitives::Curves { .. }) => {
                let [a, b] = Self::ends(primitives, prim.index as usize);
                let (oo, od) = traced.ray_to_object(o, d);
                let (t, s) = match primitives {
                    Primitives::Cones { caps, .. } => {
                        cone(oo, od, (a, b), caps[prim.index as usize], (t_min, t_max))?
                    }
                    _ => curve(oo, od, (a, b), (t_min, t_max))?,
                };
                // Along the axis: the second end's weight, as a
                // triangle's barycentric.
                return Some((t, Vec2::new(s, 0.0)));
            }
        };
        Some((t, Vec2::ZERO))
    }

    /// Kept cone or curve segment `index`'s two ends, in object space.
    fn ends(primitives: &Primitives, index: usize) -> [End; 2] {
        match primitives {
            Primitives::Cones {
                positions,
                cones,
                radii,
                ..
            } => {
                let [a, b] = cones[index].map(|v| positions[v as usize]);
                let [ra, rb] = radii[index];
                [(a, ra), (b, rb)]
            }
            Primitives::Curves {
                positions,
                radii,
                segments,
            } => {
                let v = segments[index] as usize;
                [(positions[v], radii[v]), (positions[v + 1], radii[v + 1])]
            }
            _ => unreachable!("only cones and curves have two ends"),
        }
    }

    /// The world-space unit normal at `p` on `prim`, facing against `d`.
    fn normal(&self, prim: Prim, p: Vec3, bary: Vec2, d: Vec3, facing: Option<Vec3>) -> Vec3 {
        let traced = &self.traced[prim.shape as usize];
        let n = match &traced.placed.shape.primitives {
            Primitives::Triangles {
                triangles, normals, ..
            } => {
                let tri = || triangles[prim.index as usize];
                match (normals, facing) {
                    (Some(n), _) => {
                        let [a, b, c] = tri().map(|v| n[v as usize]);
                        let object = a * (1.0 - bary.x - bary.y) + b * bary.x + c * bary.y;
                        traced.normal_to_world * object
                    }
                    // The traversal's block had it, as computed below.
                    (None, Some(facing)) => facing,
                    (None, None) => {
                        let [a, b, c] = tri().map(|v| traced.world()[v as usize]);
                        (b - a).cross(c - a)
                    }
                }
            }
            Primitives::Spheres {
                positions, spheres, ..
            } => {
                let c = positions[spheres[prim.index as usize] as usize];
                traced.normal_to_world * (traced.point_to_object(p) - c)
            }
            primitives @ (Primitives::Cones { .. } | Primitives::Curves { .. }) => {
                let [a, b] = Self::ends(primitives, prim.index as usize);
                let q = traced.point_to_object(p);
                let object = match primitives {
                    Primitives::Cones { .. } => cone_normal(a, b, q, true),
                    _ => curve_normal(a, b, q),
                };
                traced.normal_to_world * object
            }
        };
        // A normal the host gave may be zero: fall back to facing the ray.
        let n = n.try_normalize().unwrap_or(-d.normalize_or_zero());
        if n.dot(d) > 0.0 {
            -n
        } else {
            n
        }
    }

    /// Attribute `slot` at `hit`: interpolated per vertex, or the host
    /// primitive's.
    pub fn attribute(&self, hit: &Hit, slot: usize) -> Vec4 {
        let traced = &self.traced[hit.shape as usize];
        if let Some(v) = traced.placed.uniform.get(slot).copied().flatten() {
            return v;
        }
        let shape = &traced.placed.shape;
        let index = hit.index as usize;
        match shape.attributes.get(slot).and_then(Option::as_ref) {
            None => DEFAULT_ATTRIBUTE,
            Some(Attribute::PerPrimitive(values)) => {
                Vec4::from(values[shape.kept.host(index).unwrap_or(0) as usize])
            }
            Some(Attribute::PerVertex(values)) => match &shape.primitives {
                Primitives::Triangles { triangles, .. } => {
                    let [a, b, c] = triangles[index].map(|v| Vec4::from(values[v as usize]));
                    a * (1.0 - hit.bary.x - hit.bary.y) + b * hit.bary.x + c * hit.bary.y
                }
                Primitives::Spheres { spheres, .. } => Vec4::from(values[spheres[index] as usize]),
                Primitives::Cones { cones, .. } => {
                    let [a, b] = cones[index].map(|v| Vec4::from(values[v as usize]));
                    a.lerp(b, hit.bary.x)
                }
                Primitives::Curves { segments, .. } => {
                    let v = segments[index] as usize;
                    Vec4::from(values[v]).lerp(Vec4::from(values[v + 1]), hit.bary.x)
                }
            },
        }
    }

    /// The material's color at `hit`, before lighting.
    pub fn albedo(&self, hit: &Hit) -> Vec3 {
        let placed = &self.traced[hit.shape as usize].placed;
        match &placed.material.color {
            ColorSource::Constant(c) => *c,
            source => self.read(hit, source).truncate(),
        }
    }

    /// What attribute or sampler `source` gives at `hit` (a constant
    /// gives the default attribute value).
    fn read<C>(&self, hit: &Hit, source: &Source<C>) -> Vec4 {
        match source {
            Source::Constant(_) => DEFAULT_ATTRIBUTE,
            Source::Attribute(slot) => self.attribute(hit, *slot),
            Source::Sampler(s) => {
                let input = s
                    .in_attribute
                    .map_or(DEFAULT_ATTRIBUTE, |slot| self.attribute(hit, slot));
                let shape = &self.traced[hit.shape as usize].placed.shape;
                let host = shape.kept.host(hit.index as usize).unwrap_or(0);
                s.sample(input, host)
            }
        }
    }

    /// The material's opacity at `hit` before its alpha mode: its own
    /// (a constant, or the first component of an attribute or a sample)
    /// times its color's fourth component where that is an attribute or
    /// a sample, as glTF multiplies a base color's alpha in.
    pub fn opacity(&self, hit: &Hit) -> f32 {
        let material = &self.traced[hit.shape as usize].placed.material;
        let own = match &material.opacity {
            OpacitySource::Constant(a) => *a,
            source => self.read(hit, source).x,
        };
        own * self.read(hit, &material.color).w
    }

    /// What the surface at `hit` lets through.
    pub fn coverage(&self, hit: &Hit) -> Coverage {
        let material = &self.traced[hit.shape as usize].placed.material;
        material
            .fixed_coverage()
            .unwrap_or_else(|| material.alpha.coverage(self.opacity(hit)))
    }

    /// The light the first surface within `reach` of `p` along `d` lets
    /// through, for the volumes' shadow and ambient-occlusion rays: none
    /// past an opaque one, 1 - opacity past a translucent one, all where
    /// there is none.
    pub fn passes(&self, p: Vec3, d: Vec3, reach: f32) -> f32 {
        match self.hit(p, d, 0.0, reach).map(|h| self.coverage(&h)) {
            Some(Coverage::Translucent(a)) => 1.0 - a,
            Some(Coverage::Opaque | Coverage::Hidden) => 0.0,
            None => 1.0,
        }
    }

    /// What the frame's hit channels record of `hit`.
    pub fn record(&self, hit: &Hit) -> HitRecord {
        HitRecord {
            what: hit.shape,
            index: hit.index,
            normal: hit.normal.to_array(),
            albedo: self.albedo(hit).to_array(),
        }
    }

    /// The shaded color at `hit` of ray `o + t d`: as the reference
    /// device shades (an eye light blended with the color), or Lambertian
    /// under the world's directional light (or a light at the eye where
    /// the world has none) and its point and spot lights, plus the
    /// renderer's ambient light.
    pub fn shade(&self, hit: &Hit, (o, d): (Vec3, Vec3), settings: &RenderSettings) -> Vec3 {
        let albedo = self.albedo(hit);
        let pbr = self.traced[hit.shape as usize].placed.material.pbr.as_ref();
        let emitted = pbr.map_or(Vec3::ZERO, |p| p.emissive);
        let n = hit.normal;
        let v = -d.normalize_or_zero();
        if let SurfaceShading::EyeLight { blend } = settings.surface_shading {
            let facing = n.dot(v).abs().min(1.0);
            return albedo * (blend * facing + 1.0 - blend) + emitted;
        }
        let mut light = if settings.headlight {
            reflected(n, v, v, albedo, pbr)
        } else if settings.directional {
            settings.light_color * reflected(n, v, settings.light, albedo, pbr)
        } else {
            Vec3::ZERO
        };
        let p = o + d * hit.t;
        for lamp in &settings.lamps {
            let (towards, arriving) = lamp.at(p);
            light += arriving * reflected(n, v, towards, albedo, pbr);
        }
        light + albedo * settings.ambient + emitted
    }
}

/// The outward normal at `q` on the cone from `a` to `b`; with `caps`, a
/// point inside the rim of an end is on that end's disc.
fn cone_normal(a: End, b: End, q: Vec3, caps: bool) -> Vec3 {
    let length = a.0.distance(b.0);
    let axis = (b.0 - a.0) / length;
    let q = q - a.0;
    let s = q.dot(axis);
    let radial = q - axis * s;
    let slope = (b.1 - a.1) / length;
    let r = a.1 + slope * s.clamp(0.0, length);
    if caps && radial.length() < r * (1.0 - 1e-4) {
        return if s < 0.5 * length { -axis } else { axis };
    }
    radial.normalize_or_zero() - axis * slope
}

/// The outward normal at `q` on the round curve segment from `a` to `b`:
/// from the centre of the end sphere it lies on, or the tangent cone's.
fn curve_normal(a: End, b: End, q: Vec3) -> Vec3 {
    let Some((lo, hi)) = tangent_cone(a, b) else {
        return q - if a.1 >= b.1 { a.0 } else { b.0 };
    };
    let axis = b.0 - a.0;
    let s = (q - a.0).dot(axis);
    if s <= (lo.0 - a.0).dot(axis) {
        q - a.0
    } else if s >= (hi.0 - a.0).dot(axis) {
        q - b.0
    } else {
        cone_normal(lo, hi, q, false)
    }
}

#[cfg(test)]
mod tests;
