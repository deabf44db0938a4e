//! Surfaces given by primitives (triangles, spheres) beside the volumes:
//! the geometry as the host described it, checked once when it is made,
//! the material that colors it, and where an instance places it. The
//! renderers build their acceleration structures from these.

use std::sync::Arc;

use glam::{Mat4, Vec3, Vec4};
use rayon::prelude::*;
use thiserror::Error;

use super::placement::{check_affine, transformed_box, ObjectIds};
use super::sampler::Sampler;
use super::storage::{Buf, Lent};

/// The most primitives one shape holds: a primitive's index must fit the
/// 32 bits the renderers' BVH leaves store.
pub const MAX_PRIMITIVES: usize = 1 << 30;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum ShapeError {
    #[error("{what} {index} refers to vertex {vertex}; there are {count} vertices")]
    IndexOutOfRange {
        what: &'static str,
        index: usize,
        vertex: u32,
        count: usize,
    },
    #[error("vertex {index} is used and has a position that is not finite ({position})")]
    NotFinite { index: usize, position: Vec3 },
    #[error("{name} has {len} values for {count} {of}")]
    AttributeLength {
        name: String,
        len: usize,
        count: usize,
        of: &'static str,
    },
    #[error("{count} primitives; one geometry holds up to {MAX_PRIMITIVES}")]
    TooMany { count: usize },
    #[error("transform {0} is not finite or is singular")]
    BadTransform(String),
}

/// The attribute slots a material may name: `color` and `attribute0..3`.
pub const ATTRIBUTE_NAMES: [&str; 5] = [
    "color",
    "attribute0",
    "attribute1",
    "attribute2",
    "attribute3",
];

/// An attribute's values, one per vertex (interpolated across each
/// primitive) or one per primitive (as the host numbered its primitives).
/// Its values are four floats each, aligned as floats, so that a host's
/// FLOAT32_VEC4 array is read where it lies.
#[derive(Clone, Debug, PartialEq)]
pub enum Attribute {
    PerVertex(Buf<[f32; 4]>),
    PerPrimitive(Buf<[f32; 4]>),
}

impl Attribute {
    pub fn per_vertex(values: Vec<Vec4>) -> Self {
        Attribute::PerVertex(values.iter().map(Vec4::to_array).collect::<Vec<_>>().into())
    }

    pub fn per_primitive(values: Vec<Vec4>) -> Self {
        Attribute::PerPrimitive(values.iter().map(Vec4::to_array).collect::<Vec<_>>().into())
    }

    fn values(&self) -> &Buf<[f32; 4]> {
        match self {
            Attribute::PerVertex(v) | Attribute::PerPrimitive(v) => v,
        }
    }
}

/// Which host primitive each kept primitive is.
#[derive(Clone, Debug, PartialEq)]
pub enum Kept {
    /// All of the host's `n`, in its order: kept primitive i is host
    /// primitive i.
    All(usize),
    /// Kept primitive i is host primitive `[i]`: some were dropped, or a
    /// host primitive became several (a quad two triangles).
    Listed(Vec<u32>),
}

impl Kept {
    /// `list` of the host's `n` primitives, kept in order: all of
    /// them, without a list, where it is as long.
    fn listed(mut list: Vec<u32>, n: usize) -> Kept {
        if list.len() == n {
            Kept::All(n)
        } else {
            list.shrink_to_fit();
            Kept::Listed(list)
        }
    }

    pub fn len(&self) -> usize {
        match self {
            Kept::All(n) => *n,
            Kept::Listed(l) => l.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The host's number of kept primitive `kept`.
    pub fn host(&self, kept: usize) -> Option<u32> {
        match self {
            Kept::All(n) => (kept < *n).then_some(kept as u32),
            Kept::Listed(l) => l.get(kept).copied(),
        }
    }

    fn heap_bytes(&self) -> u64 {
        match self {
            Kept::All(_) => 0,
            Kept::Listed(l) => (l.capacity() * size_of::<u32>()) as u64,
        }
    }
}

/// What a shape is made of. Primitives that cannot show (zero area, zero
/// radius) are dropped when the shape is made; `source` numbers each kept
/// one as the host did, so per-primitive attributes and ids stay right.
#[derive(Clone, Debug, PartialEq)]
pub enum Primitives {
    /// Read from the host's arrays in place where it shares them.
    Triangles {
        positions: Buf<Vec3>,
        triangles: Buf<[u32; 3]>,
        /// Per vertex, if the host gave them; else each face's own.
        normals: Option<Buf<Vec3>>,
    },
    Spheres {
        positions: Vec<Vec3>,
        /// Per vertex.
        radii: Vec<f32>,
        /// The vertex of each kept sphere.
        spheres: Vec<u32>,
    },
    /// Cylinders are cones of one radius.
    Cones {
        positions: Vec<Vec3>,
        /// The two end vertices of each kept cone.
        cones: Vec<[u32; 2]>,
        /// Its radius at each end.
        radii: Vec<[f32; 2]>,
        /// Closed by a disc at the first end, and at the second.
        caps: Vec<[bool; 2]>,
    },
    /// Round linear curves: each segment the hull of the spheres at its
    /// two vertices, so that consecutive segments join smoothly.
    Curves {
        positions: Vec<Vec3>,
        /// Per vertex.
        radii: Vec<f32>,
        /// The first vertex of each kept segment; the second follows it.
        segments: Vec<u32>,
    },
}

/// One geometry: its primitives and attributes, in object space.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    pub primitives: Primitives,
    pub kept: Kept,
    /// By slot of [`ATTRIBUTE_NAMES`].
    pub attributes: [Option<Attribute>; 5],
    /// The host's `primitive.id`, by host primitive index.
    pub ids: Option<Vec<u32>>,
    /// The object-space box around every kept primitive, measured once:
    /// every frame asks for a scene's bounds.
    bounds: (Vec3, Vec3),
}

/// A shape as made, and what was dropped from it.
pub struct Made {
    pub shape: Shape,
    /// Why some primitives were dropped, if any were (for a warning).
    pub dropped: Option<String>,
}

/// What every shape checks beside its primitives.
pub struct ShapeInput {
    /// Vertices the host gave (for per-vertex attributes).
    pub vertices: usize,
    /// Primitives the host gave (for per-primitive attributes).
    pub primitives: usize,
    pub attributes: [Option<Attribute>; 5],
    pub ids: Option<Vec<u32>>,
}

impl ShapeInput {
    fn check(&self) -> Result<(), ShapeError> {
        if self.primitives > MAX_PRIMITIVES {
            return Err(ShapeError::TooMany {
                count: self.primitives,
            });
        }
        for (slot, a) in self.attributes.iter().enumerate() {
            let (len, count, of, scope) = match a {
                None => continue,
                Some(Attribute::PerVertex(v)) => (v.len(), self.vertices, "vertices", "vertex"),
                Some(Attribute::PerPrimitive(v)) => {
                    (v.len(), self.primitives, "primitives", "primitive")
                }
            };
            if len < count {
                return Err(ShapeError::AttributeLength {
                    name: format!("{scope}.{}", ATTRIBUTE_NAMES[slot]),
                    len,
                    count,
                    of,
                });
            }
        }
        if let Some(ids) = &self.ids {
            if ids.len() < self.primitives {
                return Err(ShapeError::AttributeLength {
                    name: "primitive.id".into(),
                    len: ids.len(),
                    count: self.primitives,
                    of: "primitives",
                });
            }
        }
        Ok(())
    }
}

/// That the vertices `pair` of host primitive `index` exist and are
/// finite.
fn check_used(
    positions: &[Vec3],
    pair: &[u32; 2],
    what: &'static str,
    index: usize,
) -> Result<(), ShapeError> {
    for &v in pair {
        let Some(&p) = positions.get(v as usize) else {
            return Err(ShapeError::IndexOutOfRange {
                what,
                index,
                vertex: v,
                count: positions.len(),
            });
        };
        if !p.is_finite() {
            return Err(ShapeError::NotFinite {
                index: v as usize,
                position: p,
            });
        }
    }
    Ok(())
}

fn dropped(count: usize, what: &str) -> Option<String> {
    (count > 0).then(|| format!("{count} {what} dropped"))
}

impl Shape {
    /// Triangles over `positions`, each a triple of vertex indices (host
    /// primitive `kept.host(i)` for triangle i, so quads split in two keep
    /// their number). Indices must lie in range and the vertices they use
    /// must be finite; triangles of zero area are dropped. Buffers read
    /// from the host's memory stay there unless a triangle is dropped.
    pub fn triangles(
        positions: impl Into<Buf<Vec3>>,
        triangles: impl Into<Buf<[u32; 3]>>,
        kept: Kept,
        normals: Option<Buf<Vec3>>,
        input: ShapeInput,
    ) -> Result<Made, ShapeError> {
        input.check()?;
        let (positions, triangles) = (positions.into(), triangles.into());
        let count = positions.len();
        if let Some(n) = &normals {
            if n.len() < count {
                return Err(ShapeError::AttributeLength {
                    name: "vertex.normal".into(),
                    len: n.len(),
                    count,
                    of: "vertices",
                });
            }
        }
        let n = triangles.len().min(kept.len());
        let host = |i: usize| kept.host(i).unwrap_or(i as u32) as usize;
        // Zero area relative to the edges: a sliver of a huge mesh shows.
        let flat = |tri: &[u32; 3]| {
            let [a, b, c] = tri.map(|v| positions[v as usize]);
            let area2 = (b - a).cross(c - a).length();
            let scale = (b - a).length_squared().max((c - a).length_squared());
            area2.is_nan() || area2 <= 1e-12 * scale
        };
        // Checked in chunks on every core; the first bad triangle is the
        // one reported.
        const CHUNK: usize = 1 << 16;
        let checked: Vec<Result<usize, ShapeError>> = triangles[..n]
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut flats = 0;
                for (j, tri) in chunk.iter().enumerate() {
                    for &v in tri {
                        let Some(&p) = positions.get(v as usize) else {
                            return Err(ShapeError::IndexOutOfRange {
                                what: "primitive",
                                index: host(c * CHUNK + j),
                                vertex: v,
                                count,
                            });
                        };
                        if !p.is_finite() {
                            return Err(ShapeError::NotFinite {
                                index: v as usize,
                                position: p,
                            });
                        }
                    }
                    flats += usize::from(flat(tri));
                }
                Ok(flats)
            })
            .collect();
        let mut flats = 0;
        for c in checked {
            flats += c?;
        }
        let (triangles, kept) = if flats == 0 && n == triangles.len() {
            (triangles, kept)
        } else {
            let mut list = Vec::with_capacity(n - flats);
            let mut hosts = Vec::with_capacity(n - flats);
            for (i, tri) in triangles[..n].iter().enumerate() {
                if !flat(tri) {
                    list.push(*tri);
                    hosts.push(host(i) as u32);
                }
            }
            (Buf::from(list), Kept::Listed(hosts))
        };
        Ok(Made {
            shape: Shape {
                primitives: Primitives::Triangles {
                    positions,
                    triangles,
                    normals,
                },
                kept,
                attributes: input.attributes,
                ids: input.ids,
                bounds: (Vec3::ZERO, Vec3::ZERO),
            }
            .measured(),
            dropped: dropped(flats, "triangles of zero area"),
        })
    }

    /// Spheres, one per host primitive: `index[i]` is the vertex whose
    /// position and radius sphere i takes. Indices must lie in range and
    /// the centers they use must be finite; spheres of zero, negative or
    /// non-finite radius are dropped.
    pub fn spheres(
        positions: Vec<Vec3>,
        radii: Vec<f32>,
        index: Vec<u32>,
        input: ShapeInput,
    ) -> Result<Made, ShapeError> {
        input.check()?;
        let count = positions.len().min(radii.len());
        let mut spheres = Vec::with_capacity(index.len());
        let mut source = Vec::with_capacity(index.len());
        let mut thin = 0;
        for (i, &v) in index.iter().enumerate() {
            if v as usize >= count {
                return Err(ShapeError::IndexOutOfRange {
                    what: "sphere",
                    index: i,
                    vertex: v,
                    count,
                });
            }
            let (c, r) = (positions[v as usize], radii[v as usize]);
            if !c.is_finite() {
                return Err(ShapeError::NotFinite {
                    index: v as usize,
                    position: c,
                });
            }
            if !(r.is_finite() && r > 0.0) {
                thin += 1;
                continue;
            }
            spheres.push(v);
            source.push(i as u32);
        }
        Ok(Made {
            shape: Shape {
                primitives: Primitives::Spheres {
                    positions,
                    radii,
                    spheres,
                },
                kept: Kept::listed(source, index.len()),
                attributes: input.attributes,
                ids: input.ids,
                bounds: (Vec3::ZERO, Vec3::ZERO),
            }
            .measured(),
            dropped: dropped(thin, "spheres of zero or invalid radius"),
        })
    }

    /// Cones between vertex pairs `ends` (host primitive i is pair i),
    /// of radii `radii[i]` at its two ends, with the caps asked for.
    /// Indices must lie in range and the ends they use must be finite;
    /// cones of zero length, of a negative or non-finite radius, or of
    /// zero radius at both ends are dropped. `noun` names one in
    /// messages: "cylinder" where the host sent cylinders.
    pub fn cones(
        noun: &'static str,
        positions: Vec<Vec3>,
        ends: Vec<[u32; 2]>,
        radii: Vec<[f32; 2]>,
        caps: Vec<[bool; 2]>,
        input: ShapeInput,
    ) -> Result<Made, ShapeError> {
        input.check()?;
        let mut cones = Vec::with_capacity(ends.len());
        let mut kept_radii = Vec::with_capacity(ends.len());
        let mut kept_caps = Vec::with_capacity(ends.len());
        let mut source = Vec::with_capacity(ends.len());
        let mut thin = 0;
        for (i, ((pair, r), cap)) in ends.iter().zip(&radii).zip(&caps).enumerate() {
            check_used(&positions, pair, noun, i)?;
            let length = positions[pair[0] as usize].distance(positions[pair[1] as usize]);
            let valid = r.iter().all(|r| r.is_finite() && *r >= 0.0);
            if !(valid && r[0].max(r[1]) > 0.0 && length > 0.0) {
                thin += 1;
                continue;
            }
            cones.push(*pair);
            kept_radii.push(*r);
            kept_caps.push(*cap);
            source.push(i as u32);
        }
        Ok(Made {
            shape: Shape {
                primitives: Primitives::Cones {
                    positions,
                    cones,
                    radii: kept_radii,
                    caps: kept_caps,
                },
                kept: Kept::listed(source, ends.len()),
                attributes: input.attributes,
                ids: input.ids,
                bounds: (Vec3::ZERO, Vec3::ZERO),
            }
            .measured(),
            dropped: dropped(thin, &format!("{noun}s of zero length or invalid radius")),
        })
    }

    /// Round linear curves: host segment i runs from vertex `first[i]` to
    /// the next, of the radii at its two vertices. Both vertices must
    /// exist and be finite; segments of a negative or non-finite radius,
    /// or of zero radius at both ends, are dropped.
    pub fn curves(
        positions: Vec<Vec3>,
        radii: Vec<f32>,
        first: Vec<u32>,
        input: ShapeInput,
    ) -> Result<Made, ShapeError> {
        input.check()?;
        let count = positions.len().min(radii.len());
        let mut segments = Vec::with_capacity(first.len());
        let mut source = Vec::with_capacity(first.len());
        let mut thin = 0;
        for (i, &v) in first.iter().enumerate() {
            let pair = [v, v.saturating_add(1)];
            check_used(&positions[..count], &pair, "curve segment", i)?;
            let r = pair.map(|v| radii[v as usize]);
            if !(r.iter().all(|r| r.is_finite() && *r >= 0.0) && r[0].max(r[1]) > 0.0) {
                thin += 1;
                continue;
            }
            segments.push(v);
            source.push(i as u32);
        }
        Ok(Made {
            shape: Shape {
                primitives: Primitives::Curves {
                    positions,
                    radii,
                    segments,
                },
                kept: Kept::listed(source, first.len()),
                attributes: input.attributes,
                ids: input.ids,
                bounds: (Vec3::ZERO, Vec3::ZERO),
            }
            .measured(),
            dropped: dropped(thin, "curve segments of invalid radius"),
        })
    }

    /// Primitives kept.
    pub fn len(&self) -> usize {
        self.kept.len()
    }

    pub fn is_empty(&self) -> bool {
        self.kept.is_empty()
    }

    /// The id of kept primitive `kept`: the host's `primitive.id` of it
    /// where given, else its index among the host's primitives.
    pub fn primitive_id(&self, kept: u32) -> u32 {
        let Some(host) = self.kept.host(kept as usize) else {
            return u32::MAX;
        };
        match &self.ids {
            Some(ids) => ids.get(host as usize).copied().unwrap_or(u32::MAX),
            None => host,
        }
    }

    /// Bytes its buffers hold (allocated, not only used).
    pub fn heap_bytes(&self) -> u64 {
        fn of<T>(v: &Vec<T>) -> u64 {
            (v.capacity() * size_of::<T>()) as u64
        }
        let primitives = match &self.primitives {
            Primitives::Triangles {
                positions,
                triangles,
                normals,
            } => {
                positions.heap_bytes()
                    + triangles.heap_bytes()
                    + normals.as_ref().map_or(0, Buf::heap_bytes)
            }
            Primitives::Spheres {
                positions,
                radii,
                spheres,
            } => of(positions) + of(radii) + of(spheres),
            Primitives::Cones {
                positions,
                cones,
                radii,
                caps,
            } => of(positions) + of(cones) + of(radii) + of(caps),
            Primitives::Curves {
                positions,
                radii,
                segments,
            } => of(positions) + of(radii) + of(segments),
        };
        let attributes: u64 = self
            .attributes
            .iter()
            .flatten()
            .map(|a| a.values().heap_bytes())
            .sum();
        primitives + self.kept.heap_bytes() + attributes + self.ids.as_ref().map_or(0, of)
    }

    /// The host memory it reads in place: a render registers with each.
    pub fn lenders(&self) -> impl Iterator<Item = &Arc<Lent>> {
        let primitives: [Option<&Arc<Lent>>; 3] = match &self.primitives {
            Primitives::Triangles {
                positions,
                triangles,
                normals,
            } => [
                positions.lender(),
                triangles.lender(),
                normals.as_ref().and_then(Buf::lender),
            ],
            _ => [None; 3],
        };
        let attributes = self
            .attributes
            .iter()
            .flatten()
            .filter_map(|a| a.values().lender());
        primitives.into_iter().flatten().chain(attributes)
    }

    /// Vertices the host gave.
    pub fn vertices(&self) -> usize {
        match &self.primitives {
            Primitives::Triangles { positions, .. } => positions.len(),
            Primitives::Spheres { positions, .. }
            | Primitives::Cones { positions, .. }
            | Primitives::Curves { positions, .. } => positions.len(),
        }
    }

    /// The object-space box around every kept primitive.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    fn measured(mut self) -> Self {
        self.bounds = self.measure_bounds();
        self
    }

    fn measure_bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::INFINITY;
        let mut hi = Vec3::NEG_INFINITY;
        match &self.primitives {
            Primitives::Triangles {
                positions,
                triangles,
                ..
            } => {
                // On every core: a million triangles' corners.
                let boxes = triangles.par_chunks(1 << 16).map(|chunk| {
                    let mut b = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                    for &v in chunk.iter().flatten() {
                        let p = positions[v as usize];
                        b = (b.0.min(p), b.1.max(p));
                    }
                    b
                });
                (lo, hi) = boxes.reduce(
                    || (Vec3::INFINITY, Vec3::NEG_INFINITY),
                    |a, b| (a.0.min(b.0), a.1.max(b.1)),
                );
            }
            Primitives::Spheres {
                positions,
                radii,
                spheres,
            } => {
                for &v in spheres {
                    let (c, r) = (positions[v as usize], radii[v as usize]);
                    (lo, hi) = (lo.min(c - r), hi.max(c + r));
                }
            }
            Primitives::Cones {
                positions,
                cones,
                radii,
                ..
            } => {
                for (pair, r) in cones.iter().zip(radii) {
                    let r = r[0].max(r[1]);
                    for &v in pair {
                        let p = positions[v as usize];
                        (lo, hi) = (lo.min(p - r), hi.max(p + r));
                    }
                }
            }
            Primitives::Curves {
                positions,
                radii,
                segments,
            } => {
                for &v in segments {
                    for v in [v as usize, v as usize + 1] {
                        let (p, r) = (positions[v], radii[v]);
                        (lo, hi) = (lo.min(p - r), hi.max(p + r));
                    }
                }
            }
        }
        (lo, hi)
    }
}

/// Where a material's color or number comes from.
#[derive(Clone, Debug)]
pub enum Source<C> {
    Constant(C),
    /// An attribute slot of [`ATTRIBUTE_NAMES`]; a shape without it gives
    /// ANARI's default attribute value (0, 0, 0, 1).
    Attribute(usize),
    /// A sampler of an attribute (or of the primitive).
    Sampler(Arc<Sampler>),
}

/// A color, linear RGB; from an attribute or a sampler its fourth
/// component multiplies the opacity.
pub type ColorSource = Source<Vec3>;

/// An opacity; from an attribute or a sampler its first component.
pub type OpacitySource = Source<f32>;

impl<C: PartialEq> PartialEq for Source<C> {
    /// Samplers by identity: a commit makes a new one.
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Self::Constant(a), Self::Constant(b)) => a == b,
            (Self::Attribute(a), Self::Attribute(b)) => a == b,
            (Self::Sampler(a), Self::Sampler(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }
}

impl<C> Source<C> {
    pub fn is_constant(&self) -> bool {
        matches!(self, Self::Constant(_))
    }

    /// The sampler, if it is one that reads an image.
    pub fn image_sampler(&self) -> Option<&Arc<Sampler>> {
        match self {
            Self::Sampler(s) if !s.is_affine() => Some(s),
            _ => None,
        }
    }
}

/// How a material's opacity shows (ANARI's `alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Opacity ignored.
    #[default]
    Opaque,
    /// Composited with what lies behind, in depth order.
    Blend,
    /// Drawn opaque where the opacity reaches the cutoff, else not at all.
    Mask(f32),
}

impl AlphaMode {
    pub const NAMES: [&'static str; 3] = ["opaque", "blend", "mask"];

    /// What a surface of opacity `a` lets through under this mode.
    pub fn coverage(self, a: f32) -> Coverage {
        // NaN from a host's attribute or sampler hides the surface.
        let a = if a > 0.0 { a.min(1.0) } else { 0.0 };
        match self {
            Self::Opaque => Coverage::Opaque,
            Self::Blend if a >= 1.0 => Coverage::Opaque,
            Self::Blend if a > 0.0 => Coverage::Translucent(a),
            Self::Blend => Coverage::Hidden,
            Self::Mask(cutoff) if a >= cutoff => Coverage::Opaque,
            Self::Mask(_) => Coverage::Hidden,
        }
    }
}

/// What a material lets through.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Coverage {
    Opaque,
    /// Of this opacity, in (0, 1).
    Translucent(f32),
    /// Not drawn.
    Hidden,
}

/// What ANARI's physicallyBased material adds to a color: a metal's
/// tint of its highlights, how rough the surface is and the light it
/// gives off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pbr {
    /// 0 dielectric, 1 metal.
    pub metallic: f32,
    /// 0 mirror-like, 1 fully rough.
    pub roughness: f32,
    /// Linear RGB radiance, added to whatever light the surface reflects.
    pub emissive: Vec3,
}

/// A surface's material: its color (a matte's, or a physically based
/// material's base color), opacity and how it shows, and for a
/// physically based one what it adds.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceMaterial {
    pub color: ColorSource,
    pub opacity: OpacitySource,
    pub alpha: AlphaMode,
    /// None: matte (Lambertian).
    pub pbr: Option<Pbr>,
}

impl Default for SurfaceMaterial {
    fn default() -> Self {
        Self {
            color: ColorSource::Constant(Vec3::splat(0.8)),
            opacity: OpacitySource::Constant(1.0),
            alpha: AlphaMode::Opaque,
            pbr: None,
        }
    }
}

impl SurfaceMaterial {
    /// What the surface lets through wherever it is hit, if that does not
    /// vary over it (its opacity and color are constants, or its alpha
    /// mode ignores them).
    pub fn fixed_coverage(&self) -> Option<Coverage> {
        match (&self.opacity, &self.alpha) {
            (_, AlphaMode::Opaque) => Some(Coverage::Opaque),
            (OpacitySource::Constant(a), mode) if self.color.is_constant() => {
                Some(mode.coverage(*a))
            }
            _ => None,
        }
    }
}

/// Per slot of [`ATTRIBUTE_NAMES`], the value an instance gives that
/// attribute on every surface it places, if any.
pub type Uniforms = [Option<Vec4>; 5];

/// A shape in its material, placed in the world.
#[derive(Clone, Debug)]
pub struct PlacedShape {
    pub shape: Arc<Shape>,
    pub material: SurfaceMaterial,
    /// Object to world: affine and invertible, as a volume's.
    pub transform: Mat4,
    /// The surface's `id` and its instance's.
    pub ids: ObjectIds,
    /// The values the placing instance gives every point of the shape
    /// instead of the shape's own.
    pub uniform: Uniforms,
}

impl PlacedShape {
    pub fn new(shape: Arc<Shape>, material: SurfaceMaterial, transform: Mat4) -> Self {
        Self {
            shape,
            material,
            transform,
            ids: ObjectIds::NONE,
            uniform: [None; 5],
        }
    }

    /// Why this shape cannot be placed, if it cannot.
    pub fn check(&self) -> Result<(), ShapeError> {
        check_affine(self.transform)
            .map_err(|_| ShapeError::BadTransform(format!("{}", self.transform)))
    }

    /// The world-space box around it.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        transformed_box(self.transform, self.shape.bounds())
    }

    /// The same shape (by identity) drawn and placed the same way.
    pub fn same(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.shape, &other.shape)
            && self.material == other.material
            && self.transform == other.transform
            && self.ids == other.ids
            && self.uniform == other.uniform
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(vertices: usize, primitives: usize) -> ShapeInput {
        ShapeInput {
            vertices,
            primitives,
            attributes: Default::default(),
            ids: None,
        }
    }

    #[test]
    fn triangles_report_bad_indices_and_positions_and_drop_flat_ones() {
        let p = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::splat(f32::NAN),
            Vec3::X * 2.0,
        ];
        let bad = Shape::triangles(p.clone(), vec![[0, 1, 7]], Kept::All(1), None, input(5, 1));
        assert_eq!(
            bad.err().unwrap().to_string(),
            "primitive 0 refers to vertex 7; there are 5 vertices"
        );
        let nan = Shape::triangles(p.clone(), vec![[0, 1, 3]], Kept::All(1), None, input(5, 1));
        assert!(nan
            .err()
            .unwrap()
            .to_string()
            .starts_with("vertex 3 is used"));
        // The NaN vertex is unused here; the second triangle is a line.
        let made = Shape::triangles(
            p,
            vec![[0, 1, 2], [0, 1, 4]],
            Kept::All(2),
            None,
            input(5, 2),
        )
        .unwrap();
        assert_eq!(made.shape.kept, Kept::Listed(vec![0]));
        assert_eq!(
            made.dropped.as_deref(),
            Some("1 triangles of zero area dropped")
        );
        assert_eq!(made.shape.bounds(), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
    }

    #[test]
    fn spheres_drop_zero_radii_and_check_attribute_lengths() {
        let made = Shape::spheres(
            vec![Vec3::ZERO, Vec3::X],
            vec![0.0, 0.5],
            vec![0, 1],
            input(2, 2),
        )
        .unwrap();
        assert_eq!(made.shape.kept, Kept::Listed(vec![1]));
        assert_eq!(
            made.shape.bounds(),
            (Vec3::new(0.5, -0.5, -0.5), Vec3::splat(0.5) + Vec3::X)
        );
        let mut short = input(2, 2);
        short.attributes[0] = Some(Attribute::per_vertex(vec![Vec4::ONE]));
        let e = Shape::spheres(vec![Vec3::ZERO, Vec3::X], vec![1.0, 1.0], vec![0, 1], short);
        assert_eq!(
            e.err().unwrap().to_string(),
            "vertex.color has 1 values for 2 vertices"
        );
    }
}
