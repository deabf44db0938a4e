//! Image warping for tracked displays (Buchacher's thesis, chapter 5):
//! the newest complete image shown from the newest eye, at every refresh,
//! while the next image renders. A [`Source`] is what a render kept of its
//! view (color over nothing, first-hit depth, layers); [`warp`] shows it
//! from another view of the same display. docs/warping.md derives the
//! forms for a head-mounted view and for a CAVE wall.

mod grid;
mod layers;
mod project;
mod quad;
mod timeline;

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::{UVec2, Vec2, Vec3, Vec4};
use rayon::prelude::*;

pub use layers::{surface_layer_depth, Layer, LayerBuilder, MAX_LAYERS, SOLID};
pub use project::Projector;
pub use timeline::{Refresh, RefreshSummary, Shown, Timeline};

use super::frame::filled;
use super::{Frame, FrameDesc, RenderError};
use crate::geometry::RayGen;

/// How the last image is brought to the new eye.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WarpMode {
    /// Show the last image as it is.
    None,
    /// Re-project the image as a plane through the scene's centre, parallel
    /// to the image plane (for a wall: parallel to the wall).
    #[default]
    Quad,
    /// Re-project a mesh raised to the first-hit depth map.
    Grid,
    /// Re-march the emission-absorption layers from the new eye.
    Layers,
}

impl WarpMode {
    pub const ALL: [WarpMode; 4] = [
        WarpMode::None,
        WarpMode::Quad,
        WarpMode::Grid,
        WarpMode::Layers,
    ];

    pub fn name(self) -> &'static str {
        match self {
            WarpMode::None => "none",
            WarpMode::Quad => "quad",
            WarpMode::Grid => "grid",
            WarpMode::Layers => "layers",
        }
    }
}

impl std::str::FromStr for WarpMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown warp '{s}'; expected none, quad, grid or layers"))
    }
}

/// Why a source cannot keep `layers` layers a pixel, if it cannot.
pub(crate) fn check_layers(layers: usize) -> Result<(), RenderError> {
    if layers > MAX_LAYERS {
        return Err(RenderError::Settings(format!(
            "a warp source keeps at most {MAX_LAYERS} layers per pixel, not {layers}"
        )));
    }
    Ok(())
}

/// What a render kept of its view for warping, lower-left pixel first.
/// Its pixels are read, not changed in place: a new image is a new source
/// (or a [`Source::paste`]), which is how the GPU knows to upload it.
#[derive(Clone, Debug, PartialEq)]
pub struct Source {
    pub size: UVec2,
    pub rays: RayGen,
    /// Premultiplied color over nothing.
    pub color: Vec<Vec4>,
    /// First-hit depth ([`RayGen::depth_at`]); infinite where nothing showed.
    pub depth: Vec<f32>,
    /// `k` layers per pixel, or none.
    pub layers: Vec<Layer>,
    pub k: usize,
    /// Volume samples the render took.
    pub samples: u64,
    /// Which image this is (new for each source and each paste).
    generation: u64,
}

/// Source generations, unique in the process.
static GENERATION: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

fn next_generation() -> u64 {
    GENERATION.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl Source {
    /// A source from its parts: `k` layers a pixel (or none).
    pub fn new(
        size: UVec2,
        rays: RayGen,
        color: Vec<Vec4>,
        depth: Vec<f32>,
        layers: Vec<Layer>,
        k: usize,
        samples: u64,
    ) -> Self {
        Self {
            size,
            rays,
            color,
            depth,
            layers,
            k,
            samples,
            generation: next_generation(),
        }
    }

    /// Which image this is: a new number for every source and paste.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    fn index(&self, p: UVec2) -> usize {
        p.y as usize * self.size.x as usize + p.x as usize
    }

    /// A source of `size` seen through `rays` with nothing in it yet,
    /// keeping `k` layers per pixel: what cells are pasted into.
    pub fn empty(size: UVec2, rays: RayGen, k: usize) -> Result<Self, RenderError> {
        FrameDesc::new(size).validate()?;
        let n = size.x as usize * size.y as usize;
        Ok(Self::new(
            size,
            rays,
            filled(n, Vec4::ZERO, "the warp source's color")?,
            filled(n, f32::INFINITY, "the warp source's depth")?,
            filled(n * k, Layer::default(), "the warp source's layers")?,
            k,
            0,
        ))
    }

    /// Puts `cell`, rendered through this source's rays shifted to
    /// `offset` (see [`RayGen::shifted`]), in its place.
    pub fn paste(&mut self, offset: UVec2, cell: &Source) -> Result<(), RenderError> {
        let fits = (offset + cell.size).cmple(self.size).all() && cell.k == self.k;
        if !fits {
            return Err(RenderError::Settings(format!(
                "internal: a {}x{} cell with {} layers at {offset} does not fit a {}x{} source with {}",
                cell.size.x, cell.size.y, cell.k, self.size.x, self.size.y, self.k
            )));
        }
        let (cw, k) = (cell.size.x as usize, self.k);
        for y in 0..cell.size.y as usize {
            let at = self.index(offset + UVec2::new(0, y as u32));
            let row = y * cw;
            self.color[at..at + cw].copy_from_slice(&cell.color[row..row + cw]);
            self.depth[at..at + cw].copy_from_slice(&cell.depth[row..row + cw]);
            self.layers[at * k..(at + cw) * k]
                .copy_from_slice(&cell.layers[row * k..(row + cw) * k]);
        }
        self.samples += cell.samples;
        self.generation = next_generation();
        Ok(())
    }

    /// Pixel `p`'s layers, if the source keeps layers.
    pub fn layers_at(&self, p: UVec2) -> Option<&[Layer]> {
        let i = self.index(p) * self.k;
        self.layers.get(i..i + self.k)
    }

    /// Color at image position `s` (pixels), bilinear between pixel
    /// centres; transparent outside the image.
    pub fn color_at(&self, s: Vec2) -> Vec4 {
        let q = s - Vec2::splat(0.5);
        let base = q.floor();
        let f = q - base;
        let (w, h) = (self.size.x as i64, self.size.y as i64);
        let texel = |dx: i64, dy: i64| {
            let (x, y) = (base.x as i64 + dx, base.y as i64 + dy);
            if x < 0 || y < 0 || x >= w || y >= h {
                Vec4::ZERO
            } else {
                self.color[(y * w + x) as usize]
            }
        };
        if !(s.is_finite() && s.cmpge(Vec2::ZERO).all() && s.cmple(self.size.as_vec2()).all()) {
            return Vec4::ZERO;
        }
        let bottom = texel(0, 0).lerp(texel(1, 0), f.x);
        let top = texel(0, 1).lerp(texel(1, 1), f.x);
        bottom.lerp(top, f.y)
    }

    /// This source as a frame of `desc` over `background` (straight RGBA).
    pub fn frame(&self, desc: &FrameDesc, background: Vec4) -> Result<Frame, RenderError> {
        Warped {
            size: self.size,
            color: self.color.clone(),
            depth: self.depth.clone(),
        }
        .frame(desc, background)
    }
}

/// The scene facts a warp needs besides the source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WarpSettings {
    pub mode: WarpMode,
    /// The scene's bounding box, world space.
    pub bounds: (Vec3, Vec3),
    /// Pixels between the grid's vertices.
    pub grid_spacing: u32,
    /// Steps of the layer re-march across the scene.
    pub layer_steps: u32,
    /// The opacity at which a warped pixel's depth is taken.
    pub depth_threshold: f32,
}

impl WarpSettings {
    pub fn new(mode: WarpMode, bounds: (Vec3, Vec3)) -> Self {
        Self {
            mode,
            bounds,
            grid_spacing: 4,
            layer_steps: 96,
            depth_threshold: 0.5,
        }
    }

    /// The proxy plane's point: the scene's centre.
    pub(crate) fn focus(&self) -> Vec3 {
        0.5 * (self.bounds.0 + self.bounds.1)
    }

    /// Why these settings cannot warp, if they cannot.
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |m: String| Err(RenderError::Settings(m));
        if !(1..=256).contains(&self.grid_spacing) {
            return bad(format!(
                "grid spacing must be 1 to 256 pixels, got {}",
                self.grid_spacing
            ));
        }
        if !(1..=4096).contains(&self.layer_steps) {
            return bad(format!(
                "layer steps must be 1 to 4096, got {}",
                self.layer_steps
            ));
        }
        if !(self.bounds.0.is_finite() && self.bounds.1.is_finite()) {
            return bad("the scene's bounds are not finite".into());
        }
        Ok(())
    }
}

/// A warped image: premultiplied color over nothing and depth, lower-left
/// first.
#[derive(Clone, Debug, PartialEq)]
pub struct Warped {
    pub size: UVec2,
    pub color: Vec<Vec4>,
    pub depth: Vec<f32>,
}

impl Warped {
    /// As a frame of `desc` (whose size must be this one) over `background`.
    pub fn frame(&self, desc: &FrameDesc, background: Vec4) -> Result<Frame, RenderError> {
        if desc.size != self.size {
            return Err(RenderError::Settings(format!(
                "internal: a {}x{} warp cannot fill a {}x{} frame",
                self.size.x, self.size.y, desc.size.x, desc.size.y
            )));
        }
        let mut color = filled(4 * self.color.len(), 0.0f32, "the warped frame's color")?;
        for (o, c) in color.chunks_exact_mut(4).zip(&self.color) {
            // As the renderers composite over their background.
            let out = *c + (1.0 - c.w) * background;
            o.copy_from_slice(&out.to_array());
        }
        Frame::from_linear(desc, color, desc.depth.then(|| self.depth.clone()))
    }
}

/// `source` shown from `target` (an image of `size`) by `settings.mode`.
pub fn warp(
    source: &Source,
    target: &RayGen,
    size: UVec2,
    settings: &WarpSettings,
) -> Result<Warped, RenderError> {
    warp_by(source, target, size, settings, None)
}

/// `warp`, giving up with `RenderError::Stopped` once `give_up` has
/// passed (checked between rows): a display's deadline bounds it.
pub fn warp_by(
    source: &Source,
    target: &RayGen,
    size: UVec2,
    settings: &WarpSettings,
    give_up: Option<Instant>,
) -> Result<Warped, RenderError> {
    let late = || give_up.is_some_and(|t| Instant::now() >= t);
    FrameDesc::new(size).validate()?;
    settings.validate()?;
    let bad = |m: String| RenderError::Settings(m);
    let n = size.x as usize * size.y as usize;
    if settings.mode == WarpMode::None {
        if size != source.size {
            return Err(bad(format!(
                "warp 'none' shows the {}x{} source as it is; it cannot fill {}x{}",
                source.size.x, source.size.y, size.x, size.y
            )));
        }
        return Ok(Warped {
            size,
            color: source.color.clone(),
            depth: source.depth.clone(),
        });
    }
    let from = Projector::new(&source.rays).map_err(bad)?;
    if settings.mode == WarpMode::Grid {
        let to = Projector::new(target).map_err(bad)?;
        return grid::warp(source, &from, &to, size, settings, &late);
    }
    if settings.mode == WarpMode::Layers && source.k == 0 {
        return Err(bad(
            "warp 'layers' needs a source rendered with layers".into()
        ));
    }
    let mut color = filled(n, Vec4::ZERO, "the warped color")?;
    let mut depth = filled(n, f32::INFINITY, "the warped depth")?;
    let w = size.x as usize;
    let stopped = AtomicBool::new(false);
    color
        .par_chunks_mut(w)
        .zip(depth.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, (c, d))| {
            if stopped.load(Ordering::Relaxed) || late() {
                stopped.store(true, Ordering::Relaxed);
                return;
            }
            for x in 0..w {
                let (px, py) = (x as u32, y as u32);
                (c[x], d[x]) = match settings.mode {
                    WarpMode::Layers => layers::march(source, &from, target, px, py, settings),
                    _ => quad::pixel(source, &from, target, px, py, settings),
                };
            }
        });
    if stopped.load(Ordering::Relaxed) {
        return Err(RenderError::Stopped);
    }
    Ok(Warped { size, color, depth })
}
