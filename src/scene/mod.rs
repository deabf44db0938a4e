//! What is rendered: volumes, transfer functions and the scene that pairs
//! them. Below the renderers and the ANARI object model alike, so the
//! renderers, the data readers and the device all describe a volume the
//! same way and none of them depends on another's room.

mod transfer_function;
mod volume;

use std::sync::Arc;

pub use transfer_function::{TransferFunction, TransferFunctionError, TABLE_SIZE};
pub use volume::{Filter, StructuredVolume, VolumeError, Voxels};

/// What a renderer draws: a volume classified by a transfer function.
/// Both are shared so a renderer can keep them uploaded and tell, by
/// identity, when they were replaced.
#[derive(Clone, Debug)]
pub struct Scene {
    pub volume: Arc<StructuredVolume>,
    pub transfer_function: Arc<TransferFunction>,
}

impl Scene {
    pub fn new(volume: StructuredVolume, transfer_function: TransferFunction) -> Self {
        Self {
            volume: Arc::new(volume),
            transfer_function: Arc::new(transfer_function),
        }
    }
}
