//! A frame object's state: what the engine keeps of its renders, which
//! channels the host has mapped, and the snapshot of its objects its last
//! render was made from.

use std::sync::Arc;

use crate::device::object::ObjectCell;
use crate::device::snapshot::{Epoch, FrameSnapshot};
use crate::device::types::DataType;
use crate::engine::FrameRenders;

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
    /// The slot renders fill, the inputs of the last image, the deadline
    /// renders.
    pub renders: FrameRenders,
    /// Which channels the host has mapped; a mapped frame is not rendered
    /// into, so the pointers it holds stay valid.
    pub mapped: [bool; 2],
    /// The color channel's ANARI type, if the frame has one.
    pub color_type: Option<DataType>,
    /// The frame's snapshot and the device epoch it was taken at: it
    /// stands until anything is committed, changed or released.
    pub snapshot: Option<(Epoch, Result<Arc<FrameSnapshot>, String>)>,
}

impl ObjectCell {
    /// `f` on the frame's state, if the object is a frame.
    pub fn with_frame<R>(&self, f: impl FnOnce(&mut FrameState) -> R) -> Option<R> {
        self.with_held(f)
    }
}
