//! Frames: the result slot a render worker fills and the host maps.

use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

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
    /// The colour channel's ANARI type, if the frame has one.
    pub color_type: Option<crate::device::types::DataType>,
}

/// Shared between the device and the worker rendering into the frame.
#[derive(Default)]
pub struct FrameSlot {
    state: Mutex<SlotState>,
    done: Condvar,
}

#[derive(Default)]
pub struct SlotState {
    pub busy: bool,
    pub result: Option<Result<Frame, String>>,
    pub duration: Duration,
}

impl FrameSlot {
    pub fn lock(&self) -> MutexGuard<'_, SlotState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub fn start(&self) {
        let mut s = self.lock();
        s.busy = true;
    }

    pub fn finish(&self, result: Result<Frame, String>, duration: Duration) {
        let mut s = self.lock();
        s.result = Some(result);
        s.duration = duration;
        s.busy = false;
        self.done.notify_all();
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
}
