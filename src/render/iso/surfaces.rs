//! Isosurfaces as a frame draws them: several surfaces (a geometry's
//! iso-values, a world's surfaces) each cast alone and the nearest hit
//! kept per pixel, since opaque surfaces hide what lies behind them; and
//! a panel's views interleaved subpixel by subpixel.

use std::sync::Arc;

use glam::Vec4;

use super::{IsoSettings, Panel};
use crate::render::frame::filled;
use crate::render::{Frame, FrameDesc, RenderError};
use crate::scene::PlacedVolume;

/// One iso-value of a placed field, with how it is cast and shaded.
#[derive(Clone, Debug)]
pub struct IsoSurface {
    pub placed: PlacedVolume,
    pub settings: IsoSettings,
}

impl IsoSurface {
    /// The same field (by identity: a commit makes a new one), placed and
    /// cast the same way.
    pub fn same(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.placed.volume, &other.placed.volume)
            && self.placed.transform == other.placed.transform
            && self.settings == other.settings
    }
}

/// Per pixel, the frame whose surface is nearest (smallest depth); the
/// frames are of `desc`'s size and carry depth. The result carries depth
/// only if `desc` asks for it.
pub fn nearest(frames: Vec<Frame>, desc: &FrameDesc) -> Result<Frame, RenderError> {
    let n = desc.pixels();
    let mut color = filled(4 * n, 0.0f32, "the surfaces' color")?;
    let mut depth = filled(n, f32::INFINITY, "the surfaces' depth")?;
    for (k, frame) in frames.iter().enumerate() {
        let d = frame
            .depth
            .as_ref()
            .filter(|d| d.len() == n && frame.size == desc.size)
            .ok_or_else(|| RenderError::Settings("a surface's frame lacks depth".into()))?;
        for (i, &di) in d.iter().enumerate() {
            // The first frame sets the background where nothing is hit.
            if k == 0 || di < depth[i] {
                depth[i] = di;
                let (x, y) = (i as u32 % desc.size.x, i as u32 / desc.size.x);
                color[4 * i..4 * i + 4].copy_from_slice(&frame.pixel(x, y).to_array());
            }
        }
    }
    Frame::from_linear(desc, color, desc.depth.then_some(depth))
}

/// The panel image from each view's whole image (`views[v]` seen from view
/// v, each of the panel's size): every subpixel from its view's. A panel
/// shows no alpha.
pub fn interleave(views: &[Frame], panel: &Panel) -> Result<Frame, RenderError> {
    let desc = FrameDesc::new(panel.size).with_color(panel.color);
    if views.len() != panel.views.len() || views.iter().any(|f| f.size != panel.size) {
        return Err(RenderError::Settings(format!(
            "{} view images for a panel of {} views",
            views.len(),
            panel.views.len()
        )));
    }
    let w = panel.size.x;
    let mut color = filled(4 * desc.pixels(), 0.0f32, "the panel image")?;
    for (i, out) in color.chunks_exact_mut(4).enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let mut px = Vec4::ONE;
        for c in 0..3 {
            px[c] = views[panel.view(x, y, c) as usize].pixel(x, y)[c];
        }
        out.copy_from_slice(&px.to_array());
    }
    Frame::from_linear(&desc, color, None)
}
