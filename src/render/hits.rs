//! What each pixel's depth shows: the primitive, object and instance
//! there, its normal and its albedo (ANARI's `channel.primitiveId`,
//! `channel.objectId`, `channel.instanceId`, `channel.normal` and
//! `channel.albedo`). Both renderers record a [`HitRecord`] per pixel,
//! naming the placed shape or volume by its index in the scene; the ids
//! the host gave are looked up once the frame is cast, the same way for
//! both.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::encoding::{linear_to_srgb, to_unorm8};
use crate::scene::{ObjectIds, Scene};

/// [`HitRecord::what`] of a pixel whose depth is a volume's: this bit and
/// the volume's index.
pub const WHAT_VOLUME: u32 = 1 << 31;
/// [`HitRecord::what`] of a pixel that shows nothing.
pub const WHAT_NOTHING: u32 = u32::MAX;
/// Words of one [`HitRecord`] (as the GPU writes it).
pub const HIT_WORDS: u32 = 8;

const _: () = assert!(size_of::<HitRecord>() == 4 * HIT_WORDS as usize);

/// One pixel's hit as a renderer records it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct HitRecord {
    /// A placed shape's index in the scene, `WHAT_VOLUME | v` for volume
    /// v, or `WHAT_NOTHING`.
    pub what: u32,
    /// The shape's kept primitive.
    pub index: u32,
    pub normal: [f32; 3],
    pub albedo: [f32; 3],
}

impl HitRecord {
    pub const NOTHING: Self = Self {
        what: WHAT_NOTHING,
        index: 0,
        normal: [0.0; 3],
        albedo: [0.0; 3],
    };

    /// The record of volume `v` at a point of normal `normal` and albedo
    /// `albedo`.
    pub fn volume(v: usize, normal: Vec3, albedo: Vec3) -> Self {
        Self {
            what: WHAT_VOLUME | v as u32,
            index: 0,
            normal: normal.to_array(),
            albedo: albedo.to_array(),
        }
    }

    /// The ids the host gave what this record names in `scene`: a shape's
    /// primitive as the host numbered it (or its `primitive.id`), a volume
    /// as primitive 0 (one primitive, as the reference device counts it).
    pub fn resolve(&self, scene: &Scene) -> PixelHit {
        let (primitive, ids) = if self.what == WHAT_NOTHING {
            (u32::MAX, None)
        } else if self.what & WHAT_VOLUME != 0 {
            let v = (self.what & !WHAT_VOLUME) as usize;
            (0, scene.volumes().get(v).map(|v| v.ids))
        } else {
            match scene.shapes().get(self.what as usize) {
                Some(s) => (s.shape.primitive_id(self.index), Some(s.ids)),
                None => (u32::MAX, None),
            }
        };
        match ids {
            Some(ids) => PixelHit {
                primitive,
                object: ids.object,
                instance: ids.instance,
                normal: self.normal,
                albedo: self.albedo,
            },
            None => PixelHit::NOTHING,
        }
    }
}

/// One pixel of the frame's id, normal and albedo channels.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PixelHit {
    pub primitive: u32,
    pub object: u32,
    pub instance: u32,
    /// World space, unit length, facing the camera; zero where nothing
    /// was hit.
    pub normal: [f32; 3],
    /// Linear RGB: a surface's color before lighting, a volume's
    /// transfer-function color; zero where nothing was hit.
    pub albedo: [f32; 3],
}

impl PixelHit {
    /// A pixel that shows nothing: every id UINT32 max, as ANARI asks.
    pub const NOTHING: Self = Self {
        primitive: u32::MAX,
        object: ObjectIds::NONE.object,
        instance: ObjectIds::NONE.instance,
        normal: [0.0; 3],
        albedo: [0.0; 3],
    };
}

/// The ids, normals and albedos of `records` in `scene`.
pub fn resolve(scene: &Scene, records: &[HitRecord]) -> Vec<PixelHit> {
    records.iter().map(|r| r.resolve(scene)).collect()
}

/// One of the frame's hit channels in one of its pixel formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HitChannel {
    PrimitiveId,
    ObjectId,
    InstanceId,
    NormalF32,
    /// Each component times 32767, rounded.
    NormalFixed16,
    AlbedoF32,
    AlbedoUnorm8,
    /// sRGB-encoded, 8 bits per component.
    AlbedoSrgb8,
}

impl HitChannel {
    /// The channel's pixels, lower-left first, as their format lays them
    /// out in memory.
    pub fn encode(self, hits: &[PixelHit]) -> Vec<u8> {
        let mut out = Vec::with_capacity(hits.len() * self.bytes_per_pixel());
        for h in hits {
            match self {
                HitChannel::PrimitiveId => out.extend(h.primitive.to_ne_bytes()),
                HitChannel::ObjectId => out.extend(h.object.to_ne_bytes()),
                HitChannel::InstanceId => out.extend(h.instance.to_ne_bytes()),
                HitChannel::NormalF32 => out.extend(h.normal.iter().flat_map(|c| c.to_ne_bytes())),
                HitChannel::NormalFixed16 => {
                    out.extend(h.normal.iter().flat_map(|c| {
                        ((c.clamp(-1.0, 1.0) * 32767.0).round() as i16).to_ne_bytes()
                    }))
                }
                HitChannel::AlbedoF32 => out.extend(h.albedo.iter().flat_map(|c| c.to_ne_bytes())),
                HitChannel::AlbedoUnorm8 => out.extend(h.albedo.map(to_unorm8)),
                HitChannel::AlbedoSrgb8 => {
                    out.extend(h.albedo.map(|c| to_unorm8(linear_to_srgb(c))))
                }
            }
        }
        out
    }

    pub fn bytes_per_pixel(self) -> usize {
        match self {
            HitChannel::PrimitiveId | HitChannel::ObjectId | HitChannel::InstanceId => 4,
            HitChannel::NormalF32 | HitChannel::AlbedoF32 => 12,
            HitChannel::NormalFixed16 => 6,
            HitChannel::AlbedoUnorm8 | HitChannel::AlbedoSrgb8 => 3,
        }
    }
}
