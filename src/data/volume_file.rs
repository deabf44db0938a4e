//! A volume file with a header, whatever its format: its voxels in index
//! space, the map its header gives from voxel index to world, in the
//! file's units, and the header fields `caveray inspect` shows; what every
//! reader returns.

use glam::{DMat4, Mat4};
use serde_json::Value;

use super::format::VolumeFormat;
use crate::scene::StructuredVolume;

/// A volume as a file with a header describes it.
pub struct VolumeFile {
    pub format: VolumeFormat,
    /// The voxels, origin 0 and spacing 1: `affine` places them.
    pub volume: StructuredVolume,
    /// Voxel index (i, j, k) to world (x, y, z) in `units`; RAS+ where
    /// `anatomical`.
    pub affine: DMat4,
    /// Whether `affine` is in an anatomical space turned into RAS+, so
    /// that superior is +z and anterior +y.
    pub anatomical: bool,
    /// The world's unit: `mm`, `m`, `um`, or `unknown` where the file does
    /// not say and its format has no convention.
    pub units: &'static str,
    /// The stored type's name (`int16`, `float32`, ...).
    pub dtype: &'static str,
    /// Header fields particular to the format, in the order shown.
    pub details: Vec<(&'static str, Value)>,
}

impl VolumeFile {
    /// The voxel-index-to-world map as the renderers take it.
    pub fn transform(&self) -> Mat4 {
        self.affine.as_mat4()
    }

    /// How many metres one world unit is, where the file says.
    pub fn metres_per_unit(&self) -> Option<f64> {
        match self.units {
            "m" => Some(1.0),
            "mm" => Some(1e-3),
            "um" => Some(1e-6),
            _ => None,
        }
    }
}
