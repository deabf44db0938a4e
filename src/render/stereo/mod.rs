//! Single-pass stereo by re-projection layers (Buchacher & Erdt, EGSR
//! 2017): the left eye is ray cast, its ray segments are re-projected into
//! the right eye's image through a texture array of layers, and a
//! compositing pass blends them. This module plans the layers; see
//! DESIGN.md section 5 for the equations.

mod plan;

pub use plan::{
    layer_memory, layers_for, minimal_focal_length, pixel_scale, plan_views, span_to_depth,
    span_to_infinity, span_to_sphere, HmdStereo, LayerPlan, NotEpipolar, StereoError, ViewPlan,
};
