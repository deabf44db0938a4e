//! WGSL sources, assembled from the files in shaders/: WGSL has no
//! includes, so the declarations generated from Rust (constants, uniform
//! structs) and the shared code are concatenated in front of each entry
//! file.

use super::uniforms::declarations;
use crate::render::stereo::LayerFormat;

const VOLUME: &str = include_str!("../../../shaders/volume.wgsl");
const COLOR: &str = include_str!("../../../shaders/color.wgsl");
const STEREO: &str = include_str!("../../../shaders/stereo.wgsl");
const RAYCAST: &str = include_str!("../../../shaders/raycast.wgsl");
const REPROJECT: &str = include_str!("../../../shaders/reproject.wgsl");
const COMPOSITE: &str = include_str!("../../../shaders/composite.wgsl");
const WARP: &str = include_str!("../../../shaders/warp.wgsl");
const CAPTURE: &str = include_str!("../../../shaders/capture.wgsl");
const ISO: &str = include_str!("../../../shaders/iso.wgsl");

pub(super) fn raycast() -> String {
    [declarations().as_str(), VOLUME, COLOR, RAYCAST].join("\n")
}

/// One eye with its warp layers recorded (src/render/warp/layers.rs).
pub(super) fn capture() -> String {
    [declarations().as_str(), VOLUME, COLOR, CAPTURE].join("\n")
}

/// The left eye with re-projection; the storage texture's format is part
/// of the WGSL type, so each layer format is its own module.
pub(super) fn reproject(format: LayerFormat) -> String {
    [declarations().as_str(), VOLUME, COLOR, STEREO, REPROJECT]
        .join("\n")
        .replace("LAYER_FORMAT", format.wgsl())
}

pub(super) fn composite() -> String {
    [declarations().as_str(), COLOR, STEREO, COMPOSITE].join("\n")
}

pub(super) fn warp() -> String {
    [declarations().as_str(), WARP].join("\n")
}

/// Isosurface ray casting (src/render/iso/ is its reference).
pub(super) fn iso() -> String {
    [declarations().as_str(), COLOR, ISO].join("\n")
}
