//! A volume on the GPU: its stored numbers as texels of a format that
//! holds them (8-bit and 16-bit integers as normalised texels, floats as
//! floats), the linear map from a texel to the field's value, and, where
//! the grid is longer than the adapter's largest 3D texture, the grid cut
//! into bricks packed into one atlas texture.
//!
//! Bricks carry a one-voxel apron on their high sides: every trilinear
//! cell whose low corner lies in a brick lies wholly in that brick's
//! texels, so the exact path reads its eight voxels from one brick and the
//! texture unit filters within one brick. Brick k of the grid (x fastest)
//! sits at atlas place k (x fastest as well), so no page table is needed
//! while every brick is resident.

use glam::{UVec2, UVec3};

use super::context::Context;
use crate::render::RenderError;

use crate::scene::{Scaling, Scene, StructuredVolume, Voxels};

/// Mip levels of a volume texture at most (level of detail): full
/// resolution and three halvings.
pub(super) const LOD_LEVELS: u32 = 4;

/// Bytes staged per submission when uploading, so that staging memory
/// stays bounded however large the volume is.
const UPLOAD_BYTES: usize = 64 << 20;

/// A brick's side in the atlas, apron included, unless the adapter's
/// largest 3D texture is shorter.
const BRICK_TEXELS: u32 = 64;

/// How a volume's numbers sit in texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Texel {
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
    fn of(voxels: &Voxels, norm16: bool) -> Self {
        match voxels {
            Voxels::U8(_) => Texel::Unorm8,
            Voxels::U16(_) if norm16 => Texel::Unorm16 { biased: false },
            Voxels::I16(_) if norm16 => Texel::Unorm16 { biased: true },
            _ => Texel::Float,
        }
    }

    fn format(self) -> wgpu::TextureFormat {
        match self {
            Texel::Unorm8 => wgpu::TextureFormat::R8Unorm,
            Texel::Unorm16 { .. } => wgpu::TextureFormat::R16Unorm,
            Texel::Float => wgpu::TextureFormat::R32Float,
        }
    }

    fn bytes(self) -> u64 {
        match self {
            Texel::Unorm8 => 1,
            Texel::Unorm16 { .. } => 2,
            Texel::Float => 4,
        }
    }

    /// The map from what the texture unit returns to the field's value:
    /// the volume's scaling with the format's normalisation folded in.
    fn to_value(self, scaling: Scaling) -> Scaling {
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
    fn encode(self, voxels: &Voxels, range: std::ops::Range<usize>, out: &mut Vec<u8>) {
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
    fn read(self, voxels: &Voxels, i: usize) -> f32 {
        match (voxels, self) {
            (Voxels::U8(v), _) => f32::from(v[i]) / 255.0,
            (Voxels::U16(v), Texel::Unorm16 { .. }) => f32::from(v[i]) / 65535.0,
            (Voxels::I16(v), Texel::Unorm16 { .. }) => f32::from(v[i] as u16 ^ 0x8000) / 65535.0,
            (v, _) => v.stored(i),
        }
    }

    /// A value as the texture unit returns it, back into texel bytes.
    fn write(self, t: f32, out: &mut Vec<u8>) {
        match self {
            Texel::Unorm8 => out.push((t * 255.0).round().clamp(0.0, 255.0) as u8),
            Texel::Unorm16 { .. } => {
                out.extend(((t * 65535.0).round().clamp(0.0, 65535.0) as u16).to_le_bytes())
            }
            Texel::Float => out.extend(t.to_le_bytes()),
        }
    }
}

/// A grid cut into bricks of `side` voxels (plus the apron on the axes
/// cut more than once), packed into an atlas `atlas.x` bricks wide and
/// `atlas.y` high.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Bricking {
    /// Voxels a brick covers per axis: the whole axis where it fits in one
    /// brick (a thin grid is not padded to cubes).
    pub side: UVec3,
    /// Bricks per axis of the grid.
    pub bricks: UVec3,
    /// Bricks per row and column of the atlas.
    pub atlas: UVec2,
}

impl Bricking {
    /// How a grid of `dims` is cut to fit textures of at most `max_side`
    /// texels a side: not at all where it fits whole (unless `forced`
    /// names a brick size, in texels); None where not even the bricks fit
    /// (the atlas would have to be longer than `max_side`).
    pub fn plan(dims: UVec3, max_side: u32, forced: Option<u32>) -> Option<Option<Self>> {
        if forced.is_none() && dims.max_element() <= max_side {
            return Some(None);
        }
        let texels = forced.unwrap_or(BRICK_TEXELS).min(max_side);
        if texels < 2 {
            return None;
        }
        let side = UVec3::from_array(
            dims.to_array()
                .map(|n| if n <= texels { n } else { texels - 1 }),
        );
        let bricks = (dims + side - UVec3::ONE) / side;
        let b = Self {
            side,
            bricks,
            atlas: UVec2::ONE,
        };
        let count = u64::from(b.count());
        let per_axis = UVec3::splat(max_side) / b.texels();
        let x = u64::from(per_axis.x).min(count);
        let y = u64::from(per_axis.y).min(count.div_ceil(x));
        let z = count.div_ceil(x * y);
        // No more rows, then no more columns, than the bricks fill.
        let y = count.div_ceil(x * z);
        let x = count.div_ceil(y * z);
        (z <= u64::from(per_axis.z)).then_some(Some(Self {
            atlas: UVec2::new(x as u32, y as u32),
            ..b
        }))
    }

    /// A brick's texels per axis: its side, and the apron where the axis
    /// has more than one brick.
    fn texels(self) -> UVec3 {
        self.side + UVec3::from_array(self.bricks.to_array().map(|n| u32::from(n > 1)))
    }

    fn count(self) -> u32 {
        self.bricks.x * self.bricks.y * self.bricks.z
    }

    /// The atlas texture's size in texels.
    fn atlas_dims(self) -> UVec3 {
        let rows = self.atlas.x * self.atlas.y;
        UVec3::new(self.atlas.x, self.atlas.y, self.count().div_ceil(rows)) * self.texels()
    }

    /// Where brick k's first texel lies in the atlas.
    fn place(self, k: u32) -> UVec3 {
        let (x, y) = (self.atlas.x, self.atlas.y);
        UVec3::new(k % x, (k / x) % y, k / (x * y)) * self.texels()
    }
}

/// How the shaders read one volume's texture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct TextureSlot {
    /// Texel to field value.
    pub to_value: Scaling,
    pub bricking: Option<Bricking>,
}

impl Default for TextureSlot {
    fn default() -> Self {
        Self {
            to_value: Scaling::IDENTITY,
            bricking: None,
        }
    }
}

/// A volume's texture and how to read it.
#[derive(Clone)]
pub(super) struct VolumeTexture {
    pub view: wgpu::TextureView,
    /// Texel to field value.
    pub to_value: Scaling,
    pub bricking: Option<Bricking>,
    /// Bytes the texture holds, mip levels included.
    pub bytes: u64,
}

impl VolumeTexture {
    pub fn slot(&self) -> TextureSlot {
        TextureSlot {
            to_value: self.to_value,
            bricking: self.bricking,
        }
    }
}

/// The texture `volume` takes on this adapter, and its bytes, refused
/// (before anything is allocated) where it cannot fit.
pub(super) fn layout_of(
    ctx: &Context,
    volume: &StructuredVolume,
) -> Result<(Option<Bricking>, u64), RenderError> {
    let dims = volume.dims();
    let max = ctx.limits.max_texture_dimension_3d;
    let bricking =
        Bricking::plan(dims, max, ctx.brick_texels).ok_or_else(|| RenderError::VolumeTooLarge {
            dims: dims.to_array(),
            max,
            adapter: ctx.info.name.clone(),
        })?;
    let texels = bricking.map_or(dims, Bricking::atlas_dims);
    let texel = Texel::of(volume.voxels(), ctx.norm16);
    let bytes = texels.as_u64vec3().element_product() * texel.bytes();
    Ok((bricking, bytes))
}

/// Whether one of the scene's volumes is bricked on this adapter (its
/// shaders then need the brick arithmetic).
pub(super) fn any_bricked(ctx: &Context, scene: &Scene) -> bool {
    let max = ctx.limits.max_texture_dimension_3d;
    scene.volumes().iter().any(|p| {
        matches!(
            Bricking::plan(p.volume.dims(), max, ctx.brick_texels),
            Some(Some(_))
        )
    })
}

/// Fails, before anything is allocated, if the scene's volume textures
/// cannot be made on this adapter or would pass the memory budget.
pub(super) fn check_scene(ctx: &Context, scene: &Scene) -> Result<(), RenderError> {
    let mut bytes = 0;
    for grid in scene.grids() {
        bytes += layout_of(ctx, grid)?.1;
    }
    match ctx.memory_budget {
        Some(budget) if bytes > budget => Err(RenderError::OutOfMemory {
            bytes,
            what: format!(
                "the scene's volume textures, past the GPU memory budget of {budget} bytes"
            ),
        }),
        _ => Ok(()),
    }
}

/// Uploads `volume` as its texture, with its mip chain where `mips` (level
/// of detail; bricked volumes are read at full detail only). An adapter
/// that refuses the allocation is reported as out of memory, and nothing
/// is left allocated.
pub(super) fn upload(
    ctx: &Context,
    volume: &StructuredVolume,
    mips: bool,
) -> Result<VolumeTexture, RenderError> {
    let (bricking, bytes) = layout_of(ctx, volume)?;
    let dims = volume.dims();
    let texel = Texel::of(volume.voxels(), ctx.norm16);
    let size = bricking.map_or(dims, Bricking::atlas_dims);
    let levels = match (mips, bricking) {
        (true, None) => LOD_LEVELS.min(32 - dims.max_element().leading_zeros()),
        _ => 1,
    };
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("volume"),
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
            bytes,
            what: format!(
                "a {}x{}x{} volume texture on {} ({e})",
                size.x, size.y, size.z, ctx.info.name
            ),
        });
    }
    let mut writer = Writer::new(ctx, &texture, texel);
    match bricking {
        None => writer.whole(volume.voxels(), dims)?,
        Some(b) => writer.bricks(volume.voxels(), dims, b)?,
    }
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
    Ok(VolumeTexture {
        view: texture.create_view(&Default::default()),
        to_value: texel.to_value(volume.scaling()),
        bricking,
        bytes: bytes + bytes / 7 * u64::from(levels > 1),
    })
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
struct Writer<'a> {
    ctx: &'a Context,
    texture: &'a wgpu::Texture,
    texel: Texel,
    staged: usize,
}

impl<'a> Writer<'a> {
    fn new(ctx: &'a Context, texture: &'a wgpu::Texture, texel: Texel) -> Self {
        Self {
            ctx,
            texture,
            texel,
            staged: 0,
        }
    }

    /// `bytes`, a block of `size` texels (x fastest), at `origin` of mip
    /// level `level`.
    fn put(
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
    fn finish(&mut self) -> Result<(), RenderError> {
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

    /// The grid brick by brick into the atlas; apron texels past the
    /// grid's last voxel repeat it, as clamping would.
    fn bricks(&mut self, voxels: &Voxels, dims: UVec3, b: Bricking) -> Result<(), RenderError> {
        let texels = b.texels();
        let last = dims - UVec3::ONE;
        let one = self.texel.bytes() as usize;
        let mut bytes = Vec::new();
        let mut k = 0;
        for bz in 0..b.bricks.z {
            for by in 0..b.bricks.y {
                for bx in 0..b.bricks.x {
                    let lo = UVec3::new(bx, by, bz) * b.side;
                    let x1 = (lo.x + texels.x).min(dims.x);
                    bytes.clear();
                    for z in 0..texels.z {
                        for y in 0..texels.y {
                            let (gy, gz) = ((lo.y + y).min(last.y), (lo.z + z).min(last.z));
                            let row =
                                (gy as usize + gz as usize * dims.y as usize) * dims.x as usize;
                            let end = bytes.len() + texels.x as usize * one;
                            self.texel.encode(
                                voxels,
                                row + lo.x as usize..row + x1 as usize,
                                &mut bytes,
                            );
                            let edge = bytes.len() - one;
                            while bytes.len() < end {
                                bytes.extend_from_within(edge..edge + one);
                            }
                        }
                    }
                    self.put(0, b.place(k), texels, &bytes)?;
                    k += 1;
                }
            }
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
    fn grids_that_fit_are_not_cut_unless_told() {
        let dims = UVec3::new(2048, 16, 16);
        assert_eq!(Bricking::plan(dims, 2048, None), Some(None));
        let b = Bricking::plan(dims, 2048, Some(8)).unwrap().unwrap();
        // The 16-voxel axes are cut too (the bricks are forced), with an
        // apron each.
        assert_eq!(b.side, UVec3::splat(7));
        assert_eq!(b.bricks, UVec3::new(293, 3, 3));
        assert_eq!(b.texels(), UVec3::splat(8));
    }

    #[test]
    fn bricks_cover_the_grid_and_the_atlas_fits() {
        let dims = UVec3::new(4096, 1024, 512);
        let b = Bricking::plan(dims, 2048, None).unwrap().unwrap();
        assert_eq!(b.side, UVec3::splat(63));
        assert!((b.bricks * b.side).cmpge(dims).all());
        assert!(((b.bricks - UVec3::ONE) * b.side).cmplt(dims).all());
        let atlas = b.atlas_dims();
        assert!(atlas.max_element() <= 2048, "{atlas}");
        let last = b.place(b.count() - 1) + b.texels();
        assert!(last.cmple(atlas).all());
        // Places are distinct: consecutive bricks step along the atlas.
        assert_eq!(b.place(1) - b.place(0), UVec3::new(64, 0, 0));
    }

    #[test]
    fn thin_grids_are_not_padded_to_cubes() {
        let b = Bricking::plan(UVec3::new(1 << 22, 1, 3), 2048, None)
            .unwrap()
            .unwrap();
        assert_eq!(b.side, UVec3::new(63, 1, 3));
        assert_eq!(b.texels(), UVec3::new(64, 1, 3));
        let texels = b.atlas_dims().as_u64vec3().element_product();
        assert!(texels < (3 << 22) * 11 / 10, "{texels}");
    }

    #[test]
    fn grids_whose_bricks_cannot_fit_are_refused() {
        assert_eq!(
            Bricking::plan(UVec3::new(1 << 20, 1 << 20, 64), 2048, None),
            None
        );
        assert_eq!(Bricking::plan(UVec3::new(4, 4, 4), 1, None), None);
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
