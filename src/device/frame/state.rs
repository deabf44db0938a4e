//! A frame object's state: what the engine keeps of its renders, which
//! channels the host has mapped, and the snapshot of its objects its last
//! render was made from.

use std::sync::Arc;

use crate::device::frame::HitChannels;
use crate::device::object::ObjectCell;
use crate::device::snapshot::{Epoch, FrameSnapshot};
use crate::device::types::DataType;
use crate::engine::FrameRenders;

/// Channels a host can map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    Color,
    Depth,
    /// Filled from each pixel's hit: `channel.primitiveId`, `objectId`,
    /// `instanceId`, `normal` or `albedo` by [`HIT_CHANNEL_NAMES`].
    Hit(usize),
}

/// The channels filled from each pixel's hit, by their ANARI names.
pub const HIT_CHANNEL_NAMES: [&str; 5] = [
    "channel.primitiveId",
    "channel.objectId",
    "channel.instanceId",
    "channel.normal",
    "channel.albedo",
];

/// Channels in all.
pub const CHANNELS: usize = 2 + HIT_CHANNEL_NAMES.len();

impl Channel {
    /// ANARI 1.x names, plus the pre-1.0 ones older hosts still pass.
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "channel.color" | "color" => Some(Channel::Color),
            "channel.depth" | "depth" => Some(Channel::Depth),
            _ => HIT_CHANNEL_NAMES
                .iter()
                .position(|n| *n == name || n.strip_prefix("channel.") == Some(name))
                .map(Channel::Hit),
        }
    }

    /// Its place in [`FrameState::mapped`].
    pub fn index(self) -> usize {
        match self {
            Channel::Color => 0,
            Channel::Depth => 1,
            Channel::Hit(i) => 2 + i,
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
    pub mapped: [bool; CHANNELS],
    /// The color channel's ANARI type, if the frame has one.
    pub color_type: Option<DataType>,
    /// The hit channels the last render was asked for.
    pub hit_channels: HitChannels,
    /// Each mapped hit channel's pixels, encoded at map time and kept
    /// until it is unmapped (the host holds a pointer into them).
    pub encoded: [Vec<u8>; HIT_CHANNEL_NAMES.len()],
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
