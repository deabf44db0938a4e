//! Single-pass stereo by re-projection layers (Buchacher & Erdt, EGSR
//! 2017): the left eye is ray cast, its ray segments are re-projected into
//! the right eye's image through a texture array of layers, and a
//! compositing pass blends them. `plan` sizes the layers (DESIGN.md
//! section 5), `reproject` turns a plan into what the GPU pass needs; the
//! passes are shaders/reproject.wgsl and shaders/composite.wgsl.

mod bounds;
mod hmd;
mod plan;
mod reproject;

pub use bounds::Bounds;
pub use plan::{
    layer_memory, layers_for, minimal_focal_length, pixel_scale, plan_views, span_to_depth,
    span_to_infinity, span_to_sphere, HmdStereo, LayerPlan, NotEpipolar, StereoError, ViewPlan,
};
pub use reproject::{LayerFormat, Reprojection, ReprojectionError, StereoFrames, StereoTimes};
