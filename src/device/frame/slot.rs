//! Frames: the result slot a render worker fills and the host maps.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

use super::deadline::ShownImage;
use crate::device::worker::RenderInputs;
use crate::render::Frame;

/// Channels a host can map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    Color,
    Depth,
}

impl Channel {
    /// ANARI 1.x names, plus the pre-1.0 ones older hosts still pass.
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "channel.color" | "color" => Some(Channel::Color),
            "channel.depth" | "depth" => Some(Channel::Depth),
            _ => None,
        }
    }
}

#[derive(Default)]
pub struct FrameState {
    pub slot: Arc<FrameSlot>,
    /// Which channels the host has mapped; a mapped frame is not rendered
    /// into, so the pointers it holds stay valid.
    pub mapped: [bool; 2],
    /// The color channel's ANARI type, if the frame has one.
    pub color_type: Option<crate::device::types::DataType>,
    /// What the last render was made from, while its image is good.
    pub last: Option<RenderInputs>,
    /// The background renders of a frame with a deadline.
    pub background: Arc<super::deadline::Background>,
}

impl Drop for FrameState {
    /// A frame the host has released for good: a render still running
    /// for it stops, so nobody waits on an image nobody can map.
    fn drop(&mut self) {
        self.slot.cancel();
        self.background.cancel();
    }
}

/// Shared between the device and the worker rendering into the frame.
#[derive(Default)]
pub struct FrameSlot {
    state: Mutex<SlotState>,
    done: Condvar,
    /// Set by `anariDiscardFrame`: the render in flight stops where it
    /// can (between the CPU reference's rows) and keeps no image.
    pub stop: AtomicBool,
    /// This frame's eye from a stereo pass another frame rendered, for
    /// the inputs it was made from.
    kept: Mutex<Option<Kept>>,
}

/// An image made for a frame by its stereo partner's render.
pub struct Kept {
    /// What this frame's render must ask for to be given the image.
    pub inputs: RenderInputs,
    pub frame: Frame,
    /// This eye's share of the pass.
    pub duration: Duration,
    /// The frame whose render made it.
    pub by: u64,
}

#[derive(Default)]
pub struct SlotState {
    pub busy: bool,
    pub result: Option<Result<Frame, String>>,
    pub duration: Duration,
    /// Renders the image stands for: 1 after a render, one more for each
    /// render of unchanged inputs (what an accumulating host counts).
    pub samples: u32,
    /// What a deadline frame showed; `None` for a whole render.
    pub shown: Option<ShownImage>,
}

impl FrameSlot {
    pub fn lock(&self) -> MutexGuard<'_, SlotState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub fn start(&self) {
        let mut s = self.lock();
        s.busy = true;
        self.stop.store(false, Ordering::Relaxed);
    }

    /// Whether the last render succeeded; then a render of the same
    /// inputs may keep its image.
    pub fn holds_image(&self) -> bool {
        matches!(self.lock().result, Some(Ok(_)))
    }

    /// Ends a render that kept the last image: only the duration changes.
    pub fn finish_unchanged(&self, duration: Duration) {
        let mut s = self.lock();
        s.duration = duration;
        s.samples = s.samples.saturating_add(1);
        s.busy = false;
        self.done.notify_all();
    }

    pub fn finish(&self, result: Result<Frame, String>, duration: Duration) {
        self.finish_as(result, duration, None);
    }

    /// Ends a deadline frame's presentation, saying what it showed.
    pub fn finish_shown(
        &self,
        result: Result<Frame, String>,
        duration: Duration,
        shown: ShownImage,
    ) {
        self.finish_as(result, duration, Some(shown));
    }

    fn finish_as(
        &self,
        result: Result<Frame, String>,
        duration: Duration,
        shown: Option<ShownImage>,
    ) {
        let mut s = self.lock();
        s.samples = u32::from(result.is_ok());
        s.result = Some(result);
        s.duration = duration;
        s.shown = shown;
        s.busy = false;
        self.done.notify_all();
    }

    /// Keeps `kept` for this frame's next render.
    pub fn keep(&self, kept: Kept) {
        *self.kept.lock().unwrap_or_else(|e| e.into_inner()) = Some(kept);
    }

    /// The kept image if it was made for `inputs`; a kept image for other
    /// inputs is dropped, never shown.
    pub fn take_kept(&self, inputs: &RenderInputs) -> Option<Kept> {
        let kept = self.kept.lock().unwrap_or_else(|e| e.into_inner()).take()?;
        (kept.inputs == *inputs).then_some(kept)
    }

    /// Whether a kept image waits for `inputs`.
    pub fn keeps(&self, inputs: &RenderInputs) -> bool {
        self.kept
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_ref()
            .is_some_and(|k| k.inputs == *inputs)
    }

    /// Blocks until no render is in flight; returns the state locked.
    pub fn wait(&self) -> MutexGuard<'_, SlotState> {
        let mut s = self.lock();
        while s.busy {
            s = self.done.wait(s).unwrap_or_else(|e| e.into_inner());
        }
        s
    }

    pub fn is_busy(&self) -> bool {
        self.lock().busy
    }

    /// Stops the render in flight, if any (discard, release).
    pub fn cancel(&self) {
        let s = self.lock();
        if s.busy {
            self.stop.store(true, Ordering::Relaxed);
        }
    }
}
