//! A volume on the GPU: its stored numbers as texels of a format that
//! holds them (8-bit and 16-bit integers as normalised texels, floats as
//! floats), the linear map from a texel to the field's value, and the
//! volume in one texture with its mip chain. Volumes that do not fit one
//! texture are paged (paging.rs), in texels of the same formats.

use glam::UVec3;

use super::context::Context;
use crate::render::RenderError;

use crate::scene::{Scaling, StructuredVolume, Voxels};

/// Mip levels of a volume texture at most (level of detail): full
/// resolution and three halvings.
pub(super) const LOD_LEVELS: u32 = 4;

/// Bytes staged per submission when uploading, so that staging memory
/// stays bounded however large the volume is.
const UPLOAD_BYTES: usize = 64 << 20;

/// How a volume's numbers sit in texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Texel {
    /// R8Unorm: uint8 numbers as they are.
    Unorm8,
    /// R16Unorm: uint16 numbers as they are, or int16 numbers plus 32768
    /// (exact both ways, where snorm would fold -32768 into -32767).
    Unorm16 { biased: bool },
    /// R32Float: floats, and 16-bit numbers where the adapter has no
    /// 16-bit normalised formats.
    Float,
}

impl Texel {
    pub(super) fn of(voxels: &Voxels, norm16: bool) -> Self {
        match voxels {
            Voxels::U8(_) => Texel::Unorm8,
            Voxels::U16(_) if norm16 => Texel::Unorm16 { biased: false },
            Voxels::I16(_) if norm16 => Texel::Unorm16 { biased: true },
            _ => Texel::Float,
        }
    }

    pub(super) fn format(self) -> wgpu::TextureFormat {
        match self {
            Texel::Unorm8 => wgpu::TextureFormat::R8Unorm,
            Texel::Unorm16 { .. } => wgpu::TextureFormat::R16Unorm,
            Texel::Float => wgpu::TextureFormat::R32Float,
        }
    }

    pub(super) fn bytes(self) -> u64 {
        match self {
            Texel::Unorm8 => 1,
            Texel::Unorm16 { .. } => 2,
            Texel::Float => 4,
        }
    }

    /// The map from what the texture unit returns to the field's value:
    /// the volume's scaling with the format's normalisation folded in.
    pub(super) fn to_value(self, scaling: Scaling) -> Scaling {
        let Scaling { slope, intercept } = scaling;
        match self {
            Texel::Unorm8 => Scaling {
                slope: slope * 255.0,
                intercept,
            },
            Texel::Unorm16 { biased } => Scaling {
                slope: slope * 65535.0,
                intercept: if biased {
                    intercept - 32768.0 * slope
                } else {
                    intercept
                },
            },
            Texel::Float => scaling,
        }
    }

    /// Voxels `range` of `voxels` as texel bytes, appended to `out`.
    pub(super) fn encode(self, voxels: &Voxels, range: std::ops::Range<usize>, out: &mut Vec<u8>) {
        match (voxels, self) {
            (Voxels::U8(v), _) => out.extend_from_slice(&v[range]),
            (Voxels::U16(v), Texel::Unorm16 { .. }) => {
                out.extend_from_slice(bytemuck::cast_slice(&v[range]))
            }
            (Voxels::I16(v), Texel::Unorm16 { .. }) => out.extend(
                v[range]
                    .iter()
                    .flat_map(|&s| (s as u16 ^ 0x8000).to_le_bytes()),
            ),
            (Voxels::F32(v), _) => out.extend_from_slice(bytemuck::cast_slice(&v[range])),
            (v, _) => out.extend(range.flat_map(|i| v.stored(i).to_le_bytes())),
        }
    }

    /// Voxel i as the texture unit returns it (for mip levels).
    pub(super) fn read(self, voxels: &Voxels, i: usize) -> f32 {
        match (voxels, self) {
            (Voxels::U8(v), _) => f32::from(v[i]) / 255.0,
            (Voxels::U16(v), Texel::Unorm16 { .. }) => f32::from(v[i]) / 65535.0,
            (Voxels::I16(v), Texel::Unorm16 { .. }) => f32::from(v[i] as u16 ^ 0x8000) / 65535.0,
            (v, _) => v.stored(i),
        }
    }

    /// One texel's bytes as the texture unit returns them.
    pub(super) fn decode(self, bytes: &[u8]) -> f32 {
        match self {
            Texel::Unorm8 => f32::from(bytes[0]) / 255.0,
            Texel::Unorm16 { .. } => f32::from(u16::from_le_bytes([bytes[0], bytes[1]])) / 65535.0,
            Texel::Float => f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
        }
    }

    /// A value as the texture unit returns it, back into texel bytes.
    pub(super) fn write(self, t: f32, out: &mut Vec<u8>) {
        match self {
            Texel::Unorm8 => out.push((t * 255.0).round().clamp(0.0, 255.0) as u8),
            Texel::Unorm16 { .. } => {
                out.extend(((t * 65535.0).round().clamp(0.0, 65535.0) as u16).to_le_bytes())
            }
            Texel::Float => out.extend(t.to_le_bytes()),
        }
    }
}

/// How the shaders read one volume: the texel-to-value map, and the page
/// table where it is paged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct TextureSlot {
    /// Texel to field value.
    pub to_value: Scaling,
    pub pages: Option<PageSlot>,
    /// An unstructured field's first word in the meshes buffer.
    pub mesh: Option<u32>,
}

impl Default for TextureSlot {
    fn default() -> Self {
        Self {
            to_value: Scaling::IDENTITY,
            pages: None,
            mesh: None,
        }
    }
}

/// Where a paged volume's page table lies and how its pool is laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct PageSlot {
    /// Its first word in the pages buffer.
    pub offset: u32,
    pub levels: u32,
    /// Voxels a brick covers per axis.
    pub side: UVec3,
    /// Slots per row and column of the pool texture.
    pub atlas: [u32; 2],
}

/// A volume's texture and how to read it.
#[derive(Clone)]
pub(super) struct VolumeTexture {
    pub view: wgpu::TextureView,
    /// Texel to field value.
    pub to_value: Scaling,
    /// Bytes the texture holds, mip levels included.
    pub bytes: u64,
}

/// Uploads `volume` as one texture, with its mip chain where `mips`
/// (level of detail). An adapter that refuses the allocation is reported
/// as out of memory, and nothing is left allocated.
pub(super) fn upload(
    ctx: &Context,
    volume: &StructuredVolume,
    mips: bool,
) -> Result<VolumeTexture, RenderError> {
    let dims = volume.dims();
    let texel = Texel::of(volume.voxels(), ctx.norm16);
    let levels = if mips {
        LOD_LEVELS.min(32 - dims.max_element().leading_zeros())
    } else {
        1
    };
    let texture = allocate(ctx, dims, levels, texel, "volume")?;
    let mut writer = Writer::new(ctx, &texture, texel);
    writer.whole(volume.voxels(), dims)?;
    let mut below: Option<(UVec3, Vec<f32>)> = None;
    for level in 1..levels {
        let values = match &below {
            Some((d, v)) => halve(*d, |i| v[i]),
            None => halve(dims, |i| texel.read(volume.voxels(), i)),
        };
        let from = below.as_ref().map_or(dims, |(d, _)| *d);
        let to = (from / 2).max(UVec3::ONE);
        let mut bytes = Vec::with_capacity(values.len() * texel.bytes() as usize);
        for &t in &values {
            texel.write(t, &mut bytes);
        }
        writer.put(level, UVec3::ZERO, to, &bytes)?;
        below = Some((to, values));
    }
    writer.finish()?;
    let bytes = dims.as_u64vec3().element_product() * texel.bytes();
    Ok(VolumeTexture {
        view: texture.create_view(&Default::default()),
        to_value: texel.to_value(volume.scaling()),
        bytes: bytes + bytes / 7 * u64::from(levels > 1),
    })
}

/// A 3D texture of `size` texels and `levels` mip levels in `texel`'s
/// format, made inside an out-of-memory error scope: an adapter that
/// refuses it is reported as out of memory, and nothing is left
/// allocated.
pub(super) fn allocate(
    ctx: &Context,
    size: UVec3,
    levels: u32,
    texel: Texel,
    label: &str,
) -> Result<wgpu::Texture, RenderError> {
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: extent(size),
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format: texel.format(),
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        texture.destroy();
        return Err(RenderError::OutOfMemory {
            bytes: size.as_u64vec3().element_product() * texel.bytes(),
            what: format!(
                "a {}x{}x{} {label} texture on {} ({e})",
                size.x, size.y, size.z, ctx.info.name
            ),
        });
    }
    Ok(texture)
}

/// A 1 x 1 x 1 volume bound in the slots a scene leaves empty.
pub(super) fn stand_in(ctx: &Context) -> wgpu::TextureView {
    ctx.device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("no volume"),
            size: extent(UVec3::ONE),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

fn extent(size: UVec3) -> wgpu::Extent3d {
    wgpu::Extent3d {
        width: size.x,
        height: size.y,
        depth_or_array_layers: size.z,
    }
}

/// Writes texel blocks into a texture, submitting and waiting whenever
/// UPLOAD_BYTES are staged, so that the host never holds more than that
/// on top of the volume.
pub(super) struct Writer<'a> {
    ctx: &'a Context,
    texture: &'a wgpu::Texture,
    texel: Texel,
    staged: usize,
}

impl<'a> Writer<'a> {
    pub(super) fn new(ctx: &'a Context, texture: &'a wgpu::Texture, texel: Texel) -> Self {
        Self {
            ctx,
            texture,
            texel,
            staged: 0,
        }
    }

    /// `bytes`, a block of `size` texels (x fastest), at `origin` of mip
    /// level `level`.
    pub(super) fn put(
        &mut self,
        level: u32,
        origin: UVec3,
        size: UVec3,
        bytes: &[u8],
    ) -> Result<(), RenderError> {
        self.ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: self.texture,
                mip_level: level,
                origin: wgpu::Origin3d {
                    x: origin.x,
                    y: origin.y,
                    z: origin.z,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(size.x * self.texel.bytes() as u32),
                rows_per_image: Some(size.y),
            },
            extent(size),
        );
        self.staged += bytes.len();
        if self.staged >= UPLOAD_BYTES {
            self.finish()?;
        }
        Ok(())
    }

    /// Submits what is staged and waits for the copy.
    pub(super) fn finish(&mut self) -> Result<(), RenderError> {
        self.staged = 0;
        self.ctx.queue.submit([]);
        self.ctx.wait()
    }

    /// The grid as it is, a slab of whole slices at a time.
    fn whole(&mut self, voxels: &Voxels, dims: UVec3) -> Result<(), RenderError> {
        let slice = dims.x as usize * dims.y as usize;
        let per_write = (UPLOAD_BYTES / (slice * self.texel.bytes() as usize)).max(1) as u32;
        let mut bytes = Vec::new();
        let mut z = 0;
        while z < dims.z {
            let n = per_write.min(dims.z - z);
            let first = z as usize * slice;
            bytes.clear();
            self.texel
                .encode(voxels, first..first + n as usize * slice, &mut bytes);
            self.put(0, UVec3::new(0, 0, z), dims.truncate().extend(n), &bytes)?;
            z += n;
        }
        Ok(())
    }
}

/// The next mip level of a grid of `dims`: dims / 2 (at least 1) texels,
/// each the mean of the 2 x 2 x 2 below it (edges clamped).
fn halve(dims: UVec3, value: impl Fn(usize) -> f32) -> Vec<f32> {
    let to = (dims / 2).max(UVec3::ONE);
    let at = |x: u32, y: u32, z: u32| {
        let (x, y, z) = (x.min(dims.x - 1), y.min(dims.y - 1), z.min(dims.z - 1));
        value(x as usize + dims.x as usize * (y as usize + dims.y as usize * z as usize))
    };
    let mut out = Vec::with_capacity((to.x * to.y * to.z) as usize);
    for z in 0..to.z {
        for y in 0..to.y {
            for x in 0..to.x {
                let mut sum = 0.0;
                for (dx, dy, dz) in (0..8).map(|k| (k & 1, (k >> 1) & 1, k >> 2)) {
                    sum += at(2 * x + dx, 2 * y + dy, 2 * z + dz);
                }
                out.push(sum / 8.0);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mip_level_is_the_mean_of_the_texels_below_it() {
        let dims = UVec3::new(4, 2, 3);
        let value = |i: usize| i as f32;
        let half = halve(dims, value);
        // 2 x 1 x 1 texels; the odd z layer is clamped into the last pair.
        assert_eq!(half.len(), 2);
        let mean = |xs: [usize; 8]| xs.iter().map(|&i| i as f32).sum::<f32>() / 8.0;
        let at = |x: usize, y: usize, z: usize| x + 4 * (y + 2 * z);
        let first = [
            at(0, 0, 0),
            at(1, 0, 0),
            at(0, 1, 0),
            at(1, 1, 0),
            at(0, 0, 1),
            at(1, 0, 1),
            at(0, 1, 1),
            at(1, 1, 1),
        ];
        assert_eq!(half[0], mean(first));
        assert_eq!(halve(UVec3::ONE, |_| 7.0), vec![7.0]);
    }

    #[test]
    fn texels_map_back_to_the_stored_values() {
        let s = Scaling {
            slope: 2.0,
            intercept: -1024.0,
        };
        let v = Voxels::I16(vec![-32768, -1, 0, 32767].into());
        let t = Texel::of(&v, true);
        let m = t.to_value(s);
        for i in 0..4 {
            let want = s.apply(v.stored(i));
            assert!((m.apply(t.read(&v, i)) - want).abs() <= 1e-3 * want.abs().max(1.0));
        }
        let v = Voxels::U8(vec![0, 7, 255].into());
        let t = Texel::of(&v, true);
        let m = t.to_value(s);
        for i in 0..3 {
            assert!((m.apply(t.read(&v, i)) - s.apply(v.stored(i))).abs() < 1e-3);
        }
    }
}
