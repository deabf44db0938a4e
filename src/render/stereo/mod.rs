//! Single-pass stereo by re-projection layers (Buchacher & Erdt, EGSR
//! 2017): the left eye is ray cast, its ray segments are re-projected into
//! the right eye's image through a texture array of layers, and a
//! compositing pass blends them. `plan` sizes the layers for their
//! setup, `epipolar` plans any pair of views from their matrices
//! (docs/reprojection_stereo.md), `layers` holds what the layers are and
//! cost, `reproject` turns a plan into what the GPU pass needs,
//! `decide` is the one place that says whether a pair can re-project and
//! `payoff` whether, by the last frames' times, it should; the
//! passes are shaders/reproject.wgsl and shaders/composite.wgsl.

mod bounds;
mod decide;
mod epipolar;
mod hmd;
mod layers;
mod payoff;
mod plan;
mod reproject;

pub use bounds::Bounds;
pub use decide::{decide, Eyes, LayerRequest, RenderFacts, TwoPasses};
pub use epipolar::{plan_views, Axis, NotEpipolar, ViewPlan};
pub use layers::{layer_count, layer_memory, layers_for, LayerCountError, LayerFormat};
pub use payoff::{PairChoice, PairCosts, PairPath};
pub use plan::{
    minimal_focal_length, paper, pixel_scale, span_to_depth, span_to_infinity, span_to_sphere,
    HmdStereo, LayerPlan, StereoError,
};
pub use reproject::{Reprojection, ReprojectionError, StereoFrames, StereoTimes, LAYER_BUDGET};
