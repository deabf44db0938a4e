//! The job the render thread runs, and what the engine keeps of a frame
//! between its renders to build the next job.

use std::sync::Arc;
use std::time::Instant;

use super::accumulation::{subpixel, MAX_SAMPLES};
use super::deadline::Background;
use super::inputs::{EyeView, Inputs};
use super::slot::FrameSlot;
use crate::render::stereo::Reprojection;
use crate::render::warp::WarpMode;
use crate::render::{Backend, ColorFormat, FrameDesc};

pub struct RenderJob {
    /// The frame's handle, which messages name.
    pub frame: u64,
    pub inputs: Arc<Inputs>,
    pub slot: Arc<FrameSlot>,
    pub on_done: Option<Box<dyn FnOnce() + Send>>,
    /// The frame's last image is still right: keep it, render nothing.
    pub unchanged: bool,
    /// One more sample k of the frame's unchanged inputs, which `inputs`
    /// then render (accumulation.rs): its image refines the last one.
    pub sample: Option<u32>,
    /// Another frame's eye to render with this one in one pass.
    pub partner: Option<Partner>,
    /// A deadline frame's background render: its image goes there, not
    /// into `slot` (which only tracks the render).
    pub background: Option<BackgroundRender>,
}

impl RenderJob {
    /// Whether the job was asked to stop (discard, release).
    pub fn stopped(&self) -> bool {
        self.slot.stopped()
    }
}

/// The other eye of a stereo pair, shown by another frame of the device:
/// rendered with the job in one re-projection pass and kept for that
/// frame's next render.
pub struct Partner {
    pub frame: u64,
    pub view: EyeView,
    pub slot: Arc<FrameSlot>,
    /// What that frame's render must ask for to be given the image.
    pub inputs: Arc<Inputs>,
    /// The pair's re-projection, planned when the partner was chosen.
    pub plan: Reprojection,
}

/// Where a deadline frame's full render goes, and what it must keep.
pub struct BackgroundRender {
    pub target: Arc<Background>,
    pub warp: WarpMode,
    /// When the camera it renders was taken.
    pub taken: Instant,
}

/// What the engine keeps of one frame between its renders.
#[derive(Default)]
pub struct FrameRenders {
    pub slot: Arc<FrameSlot>,
    /// What the last render was made from, while its image is good.
    last: Option<Arc<Inputs>>,
    /// The background renders of a frame with a deadline.
    pub background: Arc<Background>,
}

impl FrameRenders {
    /// The whole render of `inputs` into this frame. Hosts render
    /// unchanged frames again (OpenCOVER up to 64 times, to accumulate):
    /// then the last image stands, or, where the host set `accumulation`,
    /// takes one more sample of each pixel.
    pub fn job(&mut self, frame: u64, inputs: Arc<Inputs>) -> RenderJob {
        let samples = self.slot.image_samples();
        // An image rendered before all its bricks were resident is not
        // kept: the render again refines it.
        // Every rank of a data-parallel frame renders: its collectives
        // wait for all of them.
        let unchanged = self.last.as_deref() == Some(&*inputs)
            && inputs.share.is_none()
            && samples.is_some()
            && self.slot.lock().progress.is_none_or(|p| p >= 1.0);
        self.last = Some(Arc::clone(&inputs));
        let sample = samples.filter(|&n| unchanged && inputs.accumulate && n < MAX_SAMPLES);
        let (inputs, unchanged) = match sample {
            Some(k) => (Arc::new(sample_of(&inputs, k)), false),
            None => (inputs, unchanged),
        };
        RenderJob {
            frame,
            inputs,
            slot: Arc::clone(&self.slot),
            on_done: None,
            unchanged,
            sample,
            partner: None,
            background: None,
        }
    }

    /// A deadline frame's render keeps nothing for the next one.
    pub fn presenting(&mut self) {
        self.last = None;
    }

    /// Whether this frame's image of `inputs` is already made: its last
    /// render's, or one its stereo partner kept for it.
    pub fn has_image_of(&self, inputs: &Inputs) -> bool {
        (self.last.as_deref() == Some(inputs) && self.slot.holds_image()) || self.slot.keeps(inputs)
    }

    /// `anariDiscardFrame`: the render in flight stops and what was kept
    /// no longer stands for the frame's next render.
    pub fn discard(&mut self) {
        self.slot.cancel();
        self.background.cancel();
        self.last = None;
    }
}

impl Drop for FrameRenders {
    /// A frame the host has released for good: a render still running
    /// for it stops, so nobody waits on an image nobody can map.
    fn drop(&mut self) {
        self.slot.cancel();
        self.background.cancel();
    }
}

impl RenderJob {
    /// Whether rendering another frame's eye with this one could gain
    /// anything: this render makes a new image, no partner kept one for
    /// it, and the renderer may be the GPU's.
    pub fn wants_partner(&self) -> bool {
        !self.unchanged
            && self.sample.is_none()
            && self.inputs.share.is_none()
            && !self.slot.keeps(&self.inputs)
            && self.inputs.backend != Backend::Cpu
    }
}

/// What sample `k` of `inputs` renders: the views through that sample's
/// point of each pixel, color alone, in floats (the mean is quantized
/// once).
fn sample_of(inputs: &Inputs, k: u32) -> Inputs {
    Inputs {
        views: inputs.views.shifted(subpixel(k)),
        desc: FrameDesc {
            color: ColorFormat::Rgba32F,
            depth: false,
            hits: false,
            ..inputs.desc
        },
        ..inputs.clone()
    }
}
