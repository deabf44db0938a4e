use glam::{UVec2, Vec4};

use super::encoding::{linear_to_srgb, srgb8, srgb_to_linear, to_unorm8};
use super::hits::PixelHit;
use super::settings::BackgroundImage;
use super::RenderError;

/// Pixel formats of ANARI's `channel.color`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ColorFormat {
    /// UFIXED8_VEC4: linear color, 8 bits per channel.
    #[default]
    Rgba8,
    /// UFIXED8_RGBA_SRGB: sRGB-encoded color, linear alpha.
    Srgba8,
    /// FLOAT32_VEC4: linear color as floats.
    Rgba32F,
}

impl ColorFormat {
    pub fn bytes_per_pixel(self) -> u64 {
        match self {
            ColorFormat::Rgba8 | ColorFormat::Srgba8 => 4,
            ColorFormat::Rgba32F => 16,
        }
    }
    /// The code the shader switches on.
    pub(crate) fn code(self) -> u32 {
        match self {
            ColorFormat::Rgba8 => 0,
            ColorFormat::Srgba8 => 1,
            ColorFormat::Rgba32F => 2,
        }
    }
}

/// What a render call should produce.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameDesc {
    pub size: UVec2,
    pub color: ColorFormat,
    /// Also return the distance along each unit ray to the first sample
    /// that contributed (infinity where none did).
    pub depth: bool,
    /// Also return what each pixel's depth shows: the ids, normal and
    /// albedo there ([`PixelHit`]).
    pub hits: bool,
}

/// The most pixels one frame may have: 2^28 (16384 x 16384), whose
/// color, depth and working buffers on the CPU reference take about 6 GiB.
pub const MAX_FRAME_PIXELS: u64 = 1 << 28;

/// A buffer of `n` copies of `value`, or an error if the memory cannot be
/// had: a large frame on a small machine fails its render, not the host.
pub(crate) fn filled<T: Clone>(n: usize, value: T, what: &str) -> Result<Vec<T>, RenderError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| RenderError::OutOfMemory {
            bytes: (n as u64).saturating_mul(std::mem::size_of::<T>() as u64),
            what: what.to_string(),
        })?;
    v.resize(n, value);
    Ok(v)
}

impl FrameDesc {
    pub fn new(size: UVec2) -> Self {
        Self {
            size,
            color: ColorFormat::Rgba8,
            depth: false,
            hits: false,
        }
    }
    pub fn with_color(self, color: ColorFormat) -> Self {
        Self { color, ..self }
    }
    pub fn with_depth(self) -> Self {
        Self {
            depth: true,
            ..self
        }
    }
    pub fn with_hits(self) -> Self {
        Self { hits: true, ..self }
    }

    pub fn pixels(&self) -> usize {
        self.size.x as usize * self.size.y as usize
    }

    /// Why a frame of this description cannot be rendered, if it cannot:
    /// checked before anything is allocated.
    pub fn validate(&self) -> Result<(), RenderError> {
        let (w, h) = (self.size.x, self.size.y);
        if self.size.min_element() == 0 {
            return Err(RenderError::Settings(format!(
                "frame size must be at least 1x1, got {w}x{h}"
            )));
        }
        let pixels = u64::from(w) * u64::from(h);
        if pixels > MAX_FRAME_PIXELS {
            return Err(RenderError::Settings(format!(
                "a frame of {w}x{h} is {pixels} pixels; caveray renders up to {MAX_FRAME_PIXELS} (16384 x 16384) per frame"
            )));
        }
        Ok(())
    }
}

/// A rendered color channel, lower-left pixel first, rows left to right.
#[derive(Clone, Debug, PartialEq)]
pub enum ColorData {
    Rgba8(Vec<u8>),
    Srgba8(Vec<u8>),
    Rgba32F(Vec<f32>),
}

/// Linear straight RGBA as an 8-bit `format` stores it (sRGB or linear
/// color, linear alpha); a float format keeps no bytes and reads as zeros.
pub fn encoded(format: ColorFormat, c: [f32; 4]) -> [u8; 4] {
    let rgb = |x: f32| match format {
        ColorFormat::Srgba8 => srgb8(x),
        _ => to_unorm8(x),
    };
    match format {
        ColorFormat::Rgba32F => [0; 4],
        _ => [rgb(c[0]), rgb(c[1]), rgb(c[2]), to_unorm8(c[3])],
    }
}

/// The result of one render: color, optional depth and hits, lower-left
/// first.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub size: UVec2,
    pub color: ColorData,
    pub depth: Option<Vec<f32>>,
    pub hits: Option<Vec<PixelHit>>,
    /// Volume samples taken (primary and shading), for samples/s figures.
    pub samples: u64,
}

impl Frame {
    /// A frame showing only `background` (straight RGBA), for a world with
    /// nothing to render; depth is infinite everywhere.
    pub fn cleared(desc: &FrameDesc, background: Vec4) -> Self {
        let n = desc.pixels();
        let color = match desc.color {
            ColorFormat::Rgba8 => ColorData::Rgba8(background.to_array().map(to_unorm8).repeat(n)),
            ColorFormat::Srgba8 => {
                let c = background.truncate().to_array().map(linear_to_srgb);
                let px = [c[0], c[1], c[2], background.w].map(to_unorm8);
                ColorData::Srgba8(px.repeat(n))
            }
            ColorFormat::Rgba32F => ColorData::Rgba32F(background.to_array().repeat(n)),
        };
        Self {
            size: desc.size,
            color,
            depth: desc.depth.then(|| vec![f32::INFINITY; n]),
            hits: desc.hits.then(|| vec![PixelHit::NOTHING; n]),
            samples: 0,
        }
    }

    /// What a frame of `desc` shows where nothing is in front: the
    /// background image stretched over it, else the color.
    pub fn background(desc: &FrameDesc, color: Vec4, image: Option<&BackgroundImage>) -> Self {
        let mut frame = Self::cleared(desc, color);
        if let Some(image) = image {
            frame.show_background_where_missed(image);
        }
        frame
    }

    /// One frame of `desc` made of `parts`, each placed with its lower
    /// left corner at its offset (a stereo pair side by side or one above
    /// the other); pixels no part covers stay zero.
    pub fn stitched(desc: &FrameDesc, parts: &[(UVec2, Frame)]) -> Result<Frame, RenderError> {
        desc.validate()?;
        let (w, n) = (desc.size.x as usize, desc.pixels());
        fn place<T: Copy>(
            out: &mut [T],
            part: &[T],
            offset: UVec2,
            size: UVec2,
            w: usize,
            k: usize,
        ) {
            let (pw, ox) = (size.x as usize, offset.x as usize);
            for y in 0..size.y as usize {
                let row = (offset.y as usize + y) * w;
                out[k * (row + ox)..k * (row + ox + pw)]
                    .copy_from_slice(&part[k * y * pw..k * (y + 1) * pw]);
            }
        }
        let mut color = match desc.color {
            ColorFormat::Rgba8 => ColorData::Rgba8(filled(4 * n, 0, "the frame's color")?),
            ColorFormat::Srgba8 => ColorData::Srgba8(filled(4 * n, 0, "the frame's color")?),
            ColorFormat::Rgba32F => ColorData::Rgba32F(filled(4 * n, 0.0, "the frame's color")?),
        };
        let mut depth = match desc.depth {
            true => Some(filled(n, f32::INFINITY, "the frame's depth")?),
            false => None,
        };
        let mut hits = match desc.hits {
            true => Some(filled(n, PixelHit::NOTHING, "the frame's hits")?),
            false => None,
        };
        let mut samples = 0;
        for (offset, part) in parts {
            let fits = (*offset + part.size).cmple(desc.size).all();
            if !fits {
                return Err(RenderError::Settings(format!(
                    "internal: a {}x{} part at {offset} does not fit a {}x{} frame",
                    part.size.x, part.size.y, desc.size.x, desc.size.y
                )));
            }
            match (&mut color, &part.color) {
                (ColorData::Rgba8(o), ColorData::Rgba8(p))
                | (ColorData::Srgba8(o), ColorData::Srgba8(p)) => {
                    place(o, p, *offset, part.size, w, 4)
                }
                (ColorData::Rgba32F(o), ColorData::Rgba32F(p)) => {
                    place(o, p, *offset, part.size, w, 4)
                }
                _ => {
                    return Err(RenderError::Settings(
                        "internal: stitched parts differ in color format".into(),
                    ))
                }
            }
            if let (Some(o), Some(p)) = (&mut depth, &part.depth) {
                place(o, p, *offset, part.size, w, 1);
            }
            if let (Some(o), Some(p)) = (&mut hits, &part.hits) {
                place(o, p, *offset, part.size, w, 1);
            }
            samples += part.samples;
        }
        Ok(Frame {
            size: desc.size,
            color,
            depth,
            hits,
            samples,
        })
    }

    /// A frame of `desc`'s format from linear RGBA floats (4 per pixel,
    /// lower-left first) and an optional depth channel.
    pub fn from_linear(
        desc: &FrameDesc,
        color: Vec<f32>,
        depth: Option<Vec<f32>>,
    ) -> Result<Frame, RenderError> {
        if desc.color == ColorFormat::Rgba32F {
            return Ok(Frame::of(desc, ColorData::Rgba32F(color), depth));
        }
        let mut out = filled(color.len(), 0u8, "the frame's 8-bit color")?;
        for (o, c) in out.chunks_exact_mut(4).zip(color.chunks_exact(4)) {
            o.copy_from_slice(&encoded(desc.color, [c[0], c[1], c[2], c[3]]));
        }
        Frame::from_encoded(desc, out, depth)
    }

    /// A frame of `desc`'s 8-bit format from its bytes (4 per pixel, as
    /// [`encoded`] makes them, lower-left first) and an optional depth
    /// channel.
    pub fn from_encoded(
        desc: &FrameDesc,
        bytes: Vec<u8>,
        depth: Option<Vec<f32>>,
    ) -> Result<Frame, RenderError> {
        let color = match desc.color {
            ColorFormat::Rgba8 => ColorData::Rgba8(bytes),
            ColorFormat::Srgba8 => ColorData::Srgba8(bytes),
            ColorFormat::Rgba32F => {
                return Err(RenderError::Settings(
                    "a float frame has no 8-bit encoding".into(),
                ))
            }
        };
        Ok(Frame::of(desc, color, depth))
    }

    fn of(desc: &FrameDesc, color: ColorData, depth: Option<Vec<f32>>) -> Frame {
        Frame {
            size: desc.size,
            color,
            depth,
            hits: None,
            samples: 0,
        }
    }

    /// Pixel (x, y) (y = 0 is the bottom row) as linear RGBA floats.
    pub fn pixel(&self, x: u32, y: u32) -> Vec4 {
        let i = (y * self.size.x + x) as usize;
        match &self.color {
            ColorData::Rgba8(b) => unorm4(&b[4 * i..4 * i + 4]),
            ColorData::Srgba8(b) => {
                let c = unorm4(&b[4 * i..4 * i + 4]);
                Vec4::new(
                    srgb_to_linear(c.x),
                    srgb_to_linear(c.y),
                    srgb_to_linear(c.z),
                    c.w,
                )
            }
            ColorData::Rgba32F(f) => Vec4::from_slice(&f[4 * i..4 * i + 4]),
        }
    }

    /// Shows `image` (stretched over this frame) in every pixel whose
    /// depth is infinite, where the rays met nothing; in every pixel of a
    /// frame without depth.
    pub fn show_background_where_missed(&mut self, image: &BackgroundImage) {
        let w = self.size.x;
        for i in 0..self.size.x as usize * self.size.y as usize {
            if self.depth.as_ref().is_some_and(|d| d[i].is_finite()) {
                continue;
            }
            let c = image.at(i as u32 % w, i as u32 / w, self.size);
            match &mut self.color {
                ColorData::Rgba8(b) => {
                    b[4 * i..4 * i + 4].copy_from_slice(&c.to_array().map(to_unorm8));
                }
                ColorData::Srgba8(b) => {
                    let rgb = c.truncate().to_array().map(linear_to_srgb);
                    b[4 * i..4 * i + 4]
                        .copy_from_slice(&[rgb[0], rgb[1], rgb[2], c.w].map(to_unorm8));
                }
                ColorData::Rgba32F(f) => f[4 * i..4 * i + 4].copy_from_slice(&c.to_array()),
            }
        }
    }

    /// Every pixel as linear RGBA, lower-left first.
    pub fn to_linear(&self) -> Vec<Vec4> {
        (0..self.size.y)
            .flat_map(|y| (0..self.size.x).map(move |x| (x, y)))
            .map(|(x, y)| self.pixel(x, y))
            .collect()
    }

    /// Display-ready 8-bit sRGB RGBA, top row first (as image files store it).
    pub fn to_srgb8_top_down(&self) -> Vec<u8> {
        let (w, h) = (self.size.x as usize, self.size.y as usize);
        let mut out = Vec::with_capacity(4 * w * h);
        for y in (0..h).rev() {
            for x in 0..w {
                let i = y * w + x;
                match &self.color {
                    ColorData::Srgba8(b) => out.extend_from_slice(&b[4 * i..4 * i + 4]),
                    _ => {
                        let c = self.pixel(x as u32, y as u32);
                        let s = Vec4::new(
                            linear_to_srgb(c.x),
                            linear_to_srgb(c.y),
                            linear_to_srgb(c.z),
                            c.w,
                        );
                        out.extend(s.to_array().map(to_unorm8));
                    }
                }
            }
        }
        out
    }
}

fn unorm4(b: &[u8]) -> Vec4 {
    Vec4::new(b[0] as f32, b[1] as f32, b[2] as f32, b[3] as f32) / 255.0
}
