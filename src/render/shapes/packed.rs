//! A shape set laid out for a GPU: two arrays of vec4 words that
//! shaders/surface.wgsl reads. The first, which the traversal reads,
//! holds the BVH's nodes, each leaf slot's primitive and each placed
//! shape's maps and color; the second the per-primitive shading data only
//! those shapes that need it carry, and the image samplers' texels (two
//! buffers, so that each stays within what one binding holds for twice
//! the triangles).
//!
//! The layout, in vec4 words (`u` a u32 stored by its bits):
//! - node i at `2 i`: (box min, u prim_count), (box max, u first_index),
//!   as obvhs keeps them: an inner node (count 0) has its children at
//!   first_index and first_index + 1, a leaf its primitives in slots
//!   first_index up to first_index + count.
//! - slot j's primitive at `prims + 3 j`: a triangle (a, -), (b, u header),
//!   (c, u index); a sphere (centre, radius), (-, u header), (-, u index);
//!   a cone or cylinder, or a curve segment, (a, radius at a), (b, u
//!   header), (radius at b, -, -, u index). The header is kind | caps << 2
//!   | shape << 4; index is the kept primitive within its shape. Triangles
//!   are in world space, the others in object space, as the CPU traces
//!   them.
//! - shape s at `shapes + 23 s`: rows of world-to-object (3 words), of
//!   object-to-world for normals (3), (constant albedo, u shading base),
//!   (u flags, constant opacity, metallic, roughness); for a color image
//!   sampler (u dims, u texel base), (u linear, u wrap per axis), the rows
//!   of its out-transform (4) and its out-offset; then (emissive, alpha
//!   cutoff); then an opacity image sampler's 7 words as the color's;
//!   unused words are zero. Flags: bit 0 per-corner color, bit 1 the
//!   host's normals, bit 2 per-corner color image coordinates, bit 3 a
//!   physically based material (metallic, roughness, emissive), bit 4
//!   per-corner opacity, bit 5 per-corner opacity image coordinates, bit
//!   6 alphaMode blend, bit 7 mask. The constant opacity is what neither
//!   varies nor samples an image of the opacity and the color's fourth
//!   component gives (1 under alphaMode opaque).
//! - in the second array, a shape's shading at `shading base + stride k`
//!   for kept primitive
//!   k: the color at each corner (3 words, its fourth component in w) if
//!   it varies, or the image coordinates there (the sampler's in-transform
//!   applied), then each corner's normal in world space (3 words) if the
//!   host gave normals, then the opacity at each corner (1 word, x y z) if
//!   it varies, or its image coordinates (3 words). Samplers that are
//!   affine in the attribute (transform, primitive) are sampled at the
//!   corners: interpolating those is sampling the interpolated attribute.
//!   Images are read per pixel.
//! - after all shading, each image sampler's texels (x fastest), once
//!   however many shapes use it.

use glam::{Vec2, Vec3};
use obvhs::bvh2::Bvh2;

use std::sync::Arc;

use super::{Hit, ShapeSet, Tree};
use crate::render::RenderError;
use crate::scene::{
    AlphaMode, OpacitySource, Primitives, Sampler, SamplerKind, Source, SurfaceMaterial,
    DEFAULT_ATTRIBUTE,
};

/// The image sampler of a material's opacity, where its alpha mode reads
/// it.
fn opacity_image(material: &SurfaceMaterial) -> Option<&Arc<Sampler>> {
    (material.alpha != AlphaMode::Opaque)
        .then(|| material.opacity.image_sampler())
        .flatten()
}

pub const KIND_TRIANGLE: u32 = 0;
pub const KIND_SPHERE: u32 = 1;
pub const KIND_CONE: u32 = 2;
pub const KIND_CURVE: u32 = 3;
pub const FLAG_ALBEDO: u32 = 1;
pub const FLAG_NORMALS: u32 = 2;
pub const FLAG_IMAGE: u32 = 4;
pub const FLAG_PBR: u32 = 8;
pub const FLAG_OPACITY: u32 = 16;
pub const FLAG_OPACITY_IMAGE: u32 = 32;
pub const FLAG_BLEND: u32 = 64;
pub const FLAG_MASK: u32 = 128;
/// Node boxes a traversal keeps to visit later, and the most levels of a
/// tree a GPU traverses.
pub const TRAVERSAL_STACK: u32 = 64;

const NODE_WORDS: usize = 2;
const PRIM_WORDS: usize = 3;
pub const SHAPE_WORDS: usize = 23;
/// Where in a shape's words each image sampler's block begins.
pub const COLOR_IMAGE: usize = 8;
pub const OPACITY_IMAGE: usize = 16;
const IMAGE_WORDS: usize = 7;

/// The words and where each part begins.
#[derive(Debug, Default)]
pub struct Packed {
    pub words: Vec<[f32; 4]>,
    /// The shading data and texels.
    pub shading: Vec<[f32; 4]>,
    /// Nodes (0: no surfaces).
    pub nodes: u32,
    pub prims: u32,
    pub shapes: u32,
}

fn bits(u: u32) -> f32 {
    f32::from_bits(u)
}

fn word(v: Vec3, w: f32) -> [f32; 4] {
    v.extend(w).to_array()
}

impl ShapeSet {
    /// `shapes` in the layout above, over the binary BVH, or why a GPU
    /// cannot take them.
    pub fn packed(shapes: &[crate::scene::PlacedShape]) -> Result<Packed, RenderError> {
        let set = Self::build_binary(shapes)?;
        match &set.tree {
            Tree::Binary(bvh) => set.pack(bvh),
            Tree::Wide(_) => unreachable!("build_binary keeps the binary tree"),
        }
    }

    fn pack(&self, bvh: &Bvh2) -> Result<Packed, RenderError> {
        if self.prims.is_empty() {
            return Ok(Packed::default());
        }
        let depth = Self::depth(bvh);
        if depth > TRAVERSAL_STACK {
            return Err(RenderError::Settings(format!(
                "the surfaces' BVH is {depth} levels deep; the GPU traverses {TRAVERSAL_STACK} (render this world on the CPU)"
            )));
        }
        let nodes = bvh.nodes.len();
        let slots = bvh.primitive_indices.len();
        let shading: usize = self
            .traced
            .iter()
            .map(|t| Self::stride(self.flags(t)) * t.placed.shape.len())
            .sum();
        let images = self.images();
        let texels: usize = images.iter().map(|(_, texels)| texels.len()).sum();
        let total = nodes * NODE_WORDS + slots * PRIM_WORDS + self.traced.len() * SHAPE_WORDS;
        let reserve = |n: usize| {
            let mut v: Vec<[f32; 4]> = Vec::new();
            v.try_reserve_exact(n)
                .map_err(|_| RenderError::OutOfMemory {
                    bytes: (n * 16) as u64,
                    what: "the surfaces for the GPU".into(),
                })
                .map(|_| v)
        };
        let mut words = reserve(total)?;
        let mut shaded = reserve(shading + texels)?;
        for n in &bvh.nodes {
            let (lo, hi) = (Vec3::from(n.aabb.min), Vec3::from(n.aabb.max));
            words.push(word(lo, bits(n.prim_count)));
            words.push(word(hi, bits(n.first_index)));
        }
        for &id in &bvh.primitive_indices {
            let prim = self.prims[id as usize];
            let traced = &self.traced[prim.shape as usize];
            let i = prim.index as usize;
            let header = |kind: u32, caps: [bool; 2]| {
                bits(kind | u32::from(caps[0]) << 2 | u32::from(caps[1]) << 3 | prim.shape << 4)
            };
            let index = bits(prim.index);
            match &traced.placed.shape.primitives {
                Primitives::Triangles { triangles, .. } => {
                    let [a, b, c] = triangles[i].map(|v| traced.world()[v as usize]);
                    words.push(word(a, 0.0));
                    words.push(word(b, header(KIND_TRIANGLE, [false; 2])));
                    words.push(word(c, index));
                }
                Primitives::Spheres {
                    positions,
                    radii,
                    spheres,
                } => {
                    let v = spheres[i] as usize;
                    words.push(word(positions[v], radii[v]));
                    words.push(word(Vec3::ZERO, header(KIND_SPHERE, [false; 2])));
                    words.push(word(Vec3::ZERO, index));
                }
                primitives @ (Primitives::Cones { .. } | Primitives::Curves { .. }) => {
                    let [(a, ra), (b, rb)] = Self::ends(primitives, i);
                    let kind = match primitives {
                        Primitives::Cones { caps, .. } => header(KIND_CONE, caps[i]),
                        _ => header(KIND_CURVE, [false; 2]),
                    };
                    words.push(word(a, ra));
                    words.push(word(b, kind));
                    words.push([rb, 0.0, 0.0, index]);
                }
            }
        }
        let shapes = words.len();
        let mut base = 0;
        // The texels follow all shading data.
        let mut texel_bases = Vec::with_capacity(images.len());
        let mut next = shading;
        for (_, texels) in &images {
            texel_bases.push(next);
            next += texels.len();
        }
        for (s, traced) in self.traced.iter().enumerate() {
            let flags = self.flags(traced);
            let rows = traced.to_object.transpose();
            for r in 0..3 {
                words.push(rows.col(r).to_array());
            }
            let normals = traced.normal_to_world.transpose();
            for r in 0..3 {
                words.push(word(normals.col(r), 0.0));
            }
            // Where the albedo does not vary, any hit's is the shape's.
            let anywhere = Self::corner_hit(s as u32, 0, Vec2::ZERO);
            let constant = self.albedo(&anywhere);
            words.push(word(constant, bits(base as u32)));
            let material = &traced.placed.material;
            let opacity = if material.alpha == AlphaMode::Opaque {
                1.0
            } else {
                let own = match &material.opacity {
                    OpacitySource::Constant(a) => *a,
                    _ if flags & (FLAG_OPACITY | FLAG_OPACITY_IMAGE) != 0 => 1.0,
                    source => self.read(&anywhere, source).x,
                };
                let color = if flags & (FLAG_ALBEDO | FLAG_IMAGE) != 0 {
                    1.0
                } else {
                    self.read(&anywhere, &material.color).w
                };
                own * color
            };
            let pbr = material.pbr;
            let (metallic, roughness) = pbr.map_or((0.0, 1.0), |p| (p.metallic, p.roughness));
            words.push([bits(flags), opacity, metallic, roughness]);
            base += Self::stride(flags) * traced.placed.shape.len();
            let image = |sampler: Option<&Arc<Sampler>>, words: &mut Vec<[f32; 4]>| {
                let Some(sampler) = sampler else {
                    words.extend([[0.0; 4]; IMAGE_WORDS]);
                    return;
                };
                let SamplerKind::Image(image) = &sampler.kind else {
                    unreachable!("image_sampler gives image samplers only");
                };
                let at = images
                    .iter()
                    .position(|(s, _)| Arc::ptr_eq(s, sampler))
                    .map_or(0, |i| texel_bases[i]);
                let d = image.dims;
                words.push([bits(d.x), bits(d.y), bits(d.z), bits(at as u32)]);
                let w = image.wrap.map(|w| bits(w.code()));
                words.push([bits(u32::from(image.linear)), w[0], w[1], w[2]]);
                let rows = sampler.out_transform.transpose();
                for r in 0..4 {
                    words.push(rows.col(r).to_array());
                }
                words.push(sampler.out_offset.to_array());
            };
            debug_assert_eq!(words.len() - shapes, s * SHAPE_WORDS + COLOR_IMAGE);
            image(material.color.image_sampler(), &mut words);
            let cutoff = match material.alpha {
                AlphaMode::Mask(cutoff) => cutoff,
                _ => 0.0,
            };
            words.push(word(pbr.map_or(Vec3::ZERO, |p| p.emissive), cutoff));
            debug_assert_eq!(words.len() - shapes, s * SHAPE_WORDS + OPACITY_IMAGE);
            image(opacity_image(material), &mut words);
        }
        for (s, traced) in self.traced.iter().enumerate() {
            let flags = self.flags(traced);
            for index in 0..traced.placed.shape.len() as u32 {
                if flags & FLAG_ALBEDO != 0 {
                    for bary in self.corners(s) {
                        let hit = Self::corner_hit(s as u32, index, bary);
                        let color = &traced.placed.material.color;
                        shaded.push(self.read(&hit, color).to_array());
                    }
                }
                if let Some(sampler) = traced.placed.material.color.image_sampler() {
                    self.push_coordinates(s, index, sampler, &mut shaded);
                }
                if flags & FLAG_NORMALS != 0 {
                    let Primitives::Triangles {
                        triangles,
                        normals: Some(n),
                        ..
                    } = &traced.placed.shape.primitives
                    else {
                        unreachable!("FLAG_NORMALS is set on triangles with normals only");
                    };
                    for v in triangles[index as usize] {
                        shaded.push(word(traced.normal_to_world * n[v as usize], 0.0));
                    }
                }
                if flags & FLAG_OPACITY != 0 {
                    let source = &traced.placed.material.opacity;
                    let at = self.corners(s).map(|bary| {
                        self.read(&Self::corner_hit(s as u32, index, bary), source)
                            .x
                    });
                    shaded.push([at[0], at[1], at[2], 0.0]);
                }
                if let Some(sampler) = opacity_image(&traced.placed.material) {
                    self.push_coordinates(s, index, sampler, &mut shaded);
                }
            }
        }
        for (_, texels) in &images {
            shaded.extend(texels.iter().map(|t| t.to_array()));
        }
        Ok(Packed {
            words,
            shading: shaded,
            nodes: nodes as u32,
            prims: (nodes * NODE_WORDS) as u32,
            shapes: shapes as u32,
        })
    }

    /// Levels from the root to the deepest leaf, the root's counted.
    fn depth(bvh: &Bvh2) -> u32 {
        let nodes = &bvh.nodes;
        let mut deepest = 0;
        let mut stack = vec![(0usize, 1u32)];
        while let Some((i, level)) = stack.pop() {
            deepest = deepest.max(level);
            let n = &nodes[i];
            if n.prim_count == 0 {
                let first = n.first_index as usize;
                stack.push((first, level + 1));
                stack.push((first + 1, level + 1));
            }
        }
        deepest
    }

    /// The image samplers the shapes use, each once, with their texels.
    fn images(&self) -> Vec<(&Arc<Sampler>, &[glam::Vec4])> {
        let mut out: Vec<(&Arc<Sampler>, &[glam::Vec4])> = Vec::new();
        for traced in &self.traced {
            let material = &traced.placed.material;
            for sampler in [material.color.image_sampler(), opacity_image(material)]
                .into_iter()
                .flatten()
            {
                if let SamplerKind::Image(image) = &sampler.kind {
                    if !out.iter().any(|(s, _)| Arc::ptr_eq(s, sampler)) {
                        out.push((sampler, &image.texels));
                    }
                }
            }
        }
        out
    }

    /// Image `sampler`'s coordinates at each corner of kept primitive
    /// `index` of shape `s`.
    fn push_coordinates(&self, s: usize, index: u32, sampler: &Sampler, out: &mut Vec<[f32; 4]>) {
        for bary in self.corners(s) {
            let hit = Self::corner_hit(s as u32, index, bary);
            let input = sampler
                .in_attribute
                .map_or(DEFAULT_ATTRIBUTE, |slot| self.attribute(&hit, slot));
            out.push(sampler.coordinates(input).to_array());
        }
    }

    /// Whether `source` differs between a shape's corners (an image
    /// sampler aside, which is read per pixel).
    fn varies<C>(traced: &super::Traced, source: &Source<C>) -> bool {
        match source {
            Source::Constant(_) => false,
            Source::Attribute(slot) => {
                traced
                    .placed
                    .shape
                    .attributes
                    .get(*slot)
                    .is_some_and(Option::is_some)
                    && traced
                        .placed
                        .uniform
                        .get(*slot)
                        .is_some_and(Option::is_none)
            }
            Source::Sampler(s) => s.is_affine(),
        }
    }

    fn flags(&self, traced: &super::Traced) -> u32 {
        let shape = &traced.placed.shape;
        let material = &traced.placed.material;
        let varies = Self::varies(traced, &material.color);
        let image = material.color.image_sampler().is_some();
        let normals = matches!(
            &shape.primitives,
            Primitives::Triangles {
                normals: Some(_),
                ..
            }
        );
        let shown = material.alpha != AlphaMode::Opaque;
        let opacity = shown && Self::varies(traced, &material.opacity);
        let opacity_image = opacity_image(material).is_some();
        let mode = match material.alpha {
            AlphaMode::Opaque => 0,
            AlphaMode::Blend => FLAG_BLEND,
            AlphaMode::Mask(_) => FLAG_MASK,
        };
        (u32::from(varies) * FLAG_ALBEDO)
            | (u32::from(normals) * FLAG_NORMALS)
            | (u32::from(image) * FLAG_IMAGE)
            | (u32::from(material.pbr.is_some()) * FLAG_PBR)
            | (u32::from(opacity) * FLAG_OPACITY)
            | (u32::from(opacity_image) * FLAG_OPACITY_IMAGE)
            | mode
    }

    fn stride(flags: u32) -> usize {
        3 * (flags & (FLAG_ALBEDO | FLAG_IMAGE) != 0) as usize
            + 3 * (flags & FLAG_NORMALS != 0) as usize
            + (flags & FLAG_OPACITY != 0) as usize
            + 3 * (flags & FLAG_OPACITY_IMAGE != 0) as usize
    }

    /// The weights a primitive's corners have in [`Hit::bary`]: a
    /// triangle's three, a cone's or curve segment's two ends (and the
    /// second again), a sphere's one.
    fn corners(&self, shape: usize) -> [Vec2; 3] {
        match &self.traced[shape].placed.shape.primitives {
            Primitives::Triangles { .. } => [Vec2::ZERO, Vec2::X, Vec2::Y],
            Primitives::Cones { .. } | Primitives::Curves { .. } => [Vec2::ZERO, Vec2::X, Vec2::X],
            Primitives::Spheres { .. } => [Vec2::ZERO; 3],
        }
    }

    fn corner_hit(shape: u32, index: u32, bary: Vec2) -> Hit {
        Hit {
            t: 0.0,
            shape,
            index,
            bary,
            normal: Vec3::Z,
        }
    }
}
