//! What the passes upload and read back, volumes aside (volume_texture.rs):
//! transfer function tables, background images, clear-brick distances,
//! surfaces, and the frame's output buffers.

use glam::UVec2;

use wgpu::util::DeviceExt;

use super::context::Context;
use crate::render::empty_space::EmptySpace;
use crate::render::frame::{ColorData, ColorFormat, FrameDesc};
use crate::render::hits::HIT_WORDS;
use crate::render::shapes::packed::Packed;
use crate::render::{BackgroundImage, RenderError};
use crate::scene::{TransferFunction, MAX_VOLUMES, TABLE_SIZE};

/// Where one volume's clear-brick distances lie in the bricks buffer.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct BrickSlot {
    pub offset: u32,
    pub bricks: [u32; 3],
}

/// Every volume's clear-brick distances, one u32 per brick, one volume
/// after the other; and where each volume's start.
pub(super) fn bricks_buffer(
    ctx: &Context,
    spaces: &[&EmptySpace],
) -> (wgpu::Buffer, Vec<BrickSlot>) {
    let mut words: Vec<u32> = Vec::new();
    let mut slots = Vec::with_capacity(spaces.len());
    for space in spaces {
        slots.push(BrickSlot {
            offset: words.len() as u32,
            bricks: space.bricks.to_array(),
        });
        words.extend_from_slice(&space.distance);
    }
    if words.is_empty() {
        words.push(0); // storage bindings cannot be empty
    }
    let buffer = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("clear bricks"),
            contents: bytemuck::cast_slice(&words),
            usage: wgpu::BufferUsages::STORAGE,
        });
    (buffer, slots)
}

/// Where the parts of the surfaces buffer begin (render/shapes/packed.rs),
/// as the uniforms tell the shaders.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct SurfaceSlot {
    /// BVH nodes; 0: the world has no surfaces.
    pub nodes: u32,
    pub prims: u32,
    pub shapes: u32,
}

/// A world's surfaces as two storage buffers of vec4 words (the traced
/// part, the shading part), and where the first's parts begin; refused if
/// either exceeds what one binding holds.
pub(super) fn surfaces_buffers(
    ctx: &Context,
    packed: &Packed,
) -> Result<([wgpu::Buffer; 2], SurfaceSlot), RenderError> {
    let max = ctx
        .limits
        .max_storage_buffer_binding_size
        .min(ctx.limits.max_buffer_size);
    for (part, words) in [
        ("BVH and primitives", &packed.words),
        ("shading", &packed.shading),
    ] {
        let bytes = 16 * words.len() as u64;
        if bytes > max {
            return Err(RenderError::Settings(format!(
                "the world's surfaces' {part} take {bytes} bytes on the GPU, more than one buffer of {} holds ({max} bytes); render it on the CPU",
                ctx.info.name
            )));
        }
    }
    let buffer = [
        words_buffer(ctx, &packed.words),
        words_buffer(ctx, &packed.shading),
    ];
    let slot = SurfaceSlot {
        nodes: packed.nodes,
        prims: packed.prims,
        shapes: packed.shapes,
    };
    Ok((buffer, slot))
}

/// A storage buffer of u32 words that frames rewrite in place (one zero
/// word where there are none: storage bindings cannot be empty).
pub(super) fn words_u32_buffer(ctx: &Context, label: &str, words: &[u32]) -> wgpu::Buffer {
    let words = if words.is_empty() { &[0][..] } else { words };
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(words),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        })
}

/// A storage buffer of vec4 words (one zero word where there are none:
/// storage bindings cannot be empty).
pub(super) fn words_buffer(ctx: &Context, words: &[[f32; 4]]) -> wgpu::Buffer {
    let stand_in = [[0.0f32; 4]];
    let words = if words.is_empty() {
        &stand_in[..]
    } else {
        words
    };
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("surfaces"),
            contents: bytemuck::cast_slice(words),
            usage: wgpu::BufferUsages::STORAGE,
        })
}

/// A background image as an RGBA32Float texture; a 1 x 1 black one stands
/// in where there is none (the binding must exist).
pub(super) fn upload_background(
    ctx: &Context,
    image: Option<&BackgroundImage>,
) -> wgpu::TextureView {
    let (size, pixels) = match image {
        Some(i) => (i.size(), i.pixels().to_vec()),
        None => (UVec2::ONE, vec![glam::Vec4::ZERO]),
    };
    let bytes: Vec<u8> = pixels
        .iter()
        .flat_map(|c| c.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    rgba_texture(ctx, "background", size, Some(&bytes)).create_view(&Default::default())
}

/// The tables: TABLE_SIZE x 2 MAX_VOLUMES RGBA32Float; row v for volume
/// v, row MAX_VOLUMES + v the same with its opacities corrected for the
/// primary step (filtered sampling).
pub(super) fn table_texture(ctx: &Context) -> wgpu::Texture {
    rgba_texture(
        ctx,
        "transfer functions",
        UVec2::new(TABLE_SIZE as u32, 2 * MAX_VOLUMES as u32),
        None,
    )
}

/// Writes `tf`'s table into row MAX_VOLUMES + `row`, each opacity `a`
/// turned into a step's: `1 - (1 - a)^exponent`.
pub(super) fn write_stepped_table(
    ctx: &Context,
    tables: &wgpu::Texture,
    row: u32,
    tf: &TransferFunction,
    exponent: f32,
) {
    let bytes: Vec<u8> = tf
        .table()
        .iter()
        .map(|c| {
            let a = if c.w >= 1.0 {
                1.0
            } else {
                1.0 - (1.0 - c.w).powf(exponent)
            };
            [c.x, c.y, c.z, a]
        })
        .flat_map(|c| c.into_iter().flat_map(f32::to_le_bytes))
        .collect();
    let first = MAX_VOLUMES as u32 + row;
    write_rows(ctx, tables, first, UVec2::new(TABLE_SIZE as u32, 1), &bytes);
}

/// Writes `tf`'s table into row `row` of the tables.
pub(super) fn write_table(ctx: &Context, tables: &wgpu::Texture, row: u32, tf: &TransferFunction) {
    let bytes: Vec<u8> = tf
        .table()
        .iter()
        .flat_map(|c| c.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    write_rows(ctx, tables, row, UVec2::new(TABLE_SIZE as u32, 1), &bytes);
}

/// A 2D RGBA32Float texture of `size`, holding `bytes` row by row if
/// given.
fn rgba_texture(ctx: &Context, label: &str, size: UVec2, bytes: Option<&[u8]>) -> wgpu::Texture {
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size.x,
            height: size.y,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    if let Some(bytes) = bytes {
        write_rows(ctx, &texture, 0, size, bytes);
    }
    texture
}

/// Writes `size` texels of RGBA32Float, row by row, from row `first` on.
fn write_rows(ctx: &Context, texture: &wgpu::Texture, first: u32, size: UVec2, bytes: &[u8]) {
    ctx.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: first,
                z: 0,
            },
            aspect: wgpu::TextureAspect::All,
        },
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(16 * size.x),
            rows_per_image: None,
        },
        wgpu::Extent3d {
            width: size.x,
            height: size.y,
            depth_or_array_layers: 1,
        },
    );
}

/// Output buffers of one frame size and format, kept across frames.
pub(super) struct OutputBuffers {
    pub size: UVec2,
    pub format: ColorFormat,
    /// Words per pixel of `samples`: the count of volume samples, then
    /// (where the frame asks for hits) its hit record (render/hits.rs).
    pub pixel_words: u32,
    pub color: wgpu::Buffer,
    pub depth: wgpu::Buffer,
    pub samples: wgpu::Buffer,
    pub color_read: wgpu::Buffer,
    pub depth_read: wgpu::Buffer,
    pub samples_read: wgpu::Buffer,
}

impl OutputBuffers {
    pub fn new(ctx: &Context, size: UVec2, format: ColorFormat, hits: bool) -> Self {
        let pixels = u64::from(size.x) * u64::from(size.y);
        let pixel_words = pixel_words(hits);
        let storage = |label, bytes| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let readable = |label, bytes| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let color_bytes = pixels * format.bytes_per_pixel();
        Self {
            size,
            format,
            pixel_words,
            color: storage("color", color_bytes),
            depth: storage("depth", 4 * pixels),
            samples: storage("samples", 4 * pixels * u64::from(pixel_words)),
            color_read: readable("color read-back", color_bytes),
            depth_read: readable("depth read-back", 4 * pixels),
            samples_read: readable("samples read-back", 4 * pixels * u64::from(pixel_words)),
        }
    }

    /// Whether these buffers fit a frame of `desc`.
    pub fn fit(&self, desc: &FrameDesc) -> bool {
        self.size == desc.size
            && self.format == desc.color
            && self.pixel_words == pixel_words(desc.hits)
    }

    pub fn color_bytes(&self) -> u64 {
        self.color.size()
    }
    /// Size of the depth buffer.
    pub fn scalar_bytes(&self) -> u64 {
        self.depth.size()
    }
}

/// Words per pixel of the samples buffer of a frame with or without hits.
pub(super) fn pixel_words(hits: bool) -> u32 {
    1 + if hits { HIT_WORDS } else { 0 }
}

pub(super) fn color_data(format: ColorFormat, bytes: Vec<u8>) -> ColorData {
    match format {
        ColorFormat::Rgba8 => ColorData::Rgba8(bytes),
        ColorFormat::Srgba8 => ColorData::Srgba8(bytes),
        ColorFormat::Rgba32F => ColorData::Rgba32F(floats(&bytes)),
    }
}

pub(super) fn floats(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}
