//! What the GPU's re-projection path needs from the planner: the right
//! eye's pixel column as a function of a world point, the whole-pixel
//! offsets every left column's segments fall in, the layer count and the
//! layer format; and what it gives back.

use glam::{DVec4, UVec2, Vec4};
use thiserror::Error;

use super::bounds::Bounds;
use super::layers::{layer_count, layer_memory, LayerCountError, LayerFormat};
use super::plan::{plan_views, NotEpipolar, ViewPlan};
use crate::geometry::MatrixCamera;
use crate::render::Frame;

/// Why a view pair renders in two passes instead.
#[derive(Debug, Error, PartialEq)]
pub enum ReprojectionError {
    #[error("re-projection does not apply: {0}")]
    NotEpipolar(#[from] NotEpipolar),
    #[error(transparent)]
    Layers(#[from] LayerCountError),
    #[error("image must be at least 1x1, got {}x{}", .0.x, .0.y)]
    EmptyImage(UVec2),
}

/// A planned re-projection of the left eye's rays into the right eye.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reprojection {
    pub size: UVec2,
    pub plan: ViewPlan,
    /// Layers allocated: the plan's, or more if asked for.
    pub layers: u32,
    pub format: LayerFormat,
    /// Right-eye pixel x of world point p is `right_x . (p, 1) / right_w . (p, 1)`.
    pub right_x: Vec4,
    pub right_w: Vec4,
}

impl Reprojection {
    /// Plans the pair for an image of `size` and a scene inside `bounds`.
    /// `layers: None` takes the planned count.
    pub fn new(
        left: &MatrixCamera,
        right: &MatrixCamera,
        size: UVec2,
        bounds: Bounds,
        layers: Option<u32>,
        format: LayerFormat,
    ) -> Result<Self, ReprojectionError> {
        if size.min_element() == 0 {
            return Err(ReprojectionError::EmptyImage(size));
        }
        let plan = plan_views(left, right, size.x, size.y, bounds)?;
        let layers = layer_count(layers, plan.layers, || {
            format!("offsets {}..={}", plan.near_px, plan.far_px)
        })?;
        let m = right.proj() * right.view();
        let (row_x, row_w) = (m.row(0), m.row(3));
        // NDC x in [-1, 1] to pixel x with centres on whole numbers.
        let w = f64::from(size.x);
        let right_x: DVec4 = 0.5 * w * (row_x + row_w) - 0.5 * row_w;
        Ok(Self {
            size,
            plan,
            layers,
            format,
            right_x: right_x.as_vec4(),
            right_w: row_w.as_vec4(),
        })
    }

    /// The first left column cast: right pixels near the left border need
    /// columns left of the image when far points shift right.
    pub fn first_column(&self) -> i32 {
        (-self.plan.far_px).min(0)
    }
    /// Left columns cast: the image plus what the right eye sees beyond it.
    pub fn columns(&self) -> u32 {
        let w = self.size.x as i32;
        let last = (w - 1).max(w - 1 - self.plan.near_px);
        (last - self.first_column() + 1) as u32
    }
    /// Bytes of the layers.
    pub fn memory(&self) -> u64 {
        layer_memory(self.size, self.layers, self.format)
    }
}

/// GPU time of each pass, in milliseconds (submission to completion).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StereoTimes {
    /// The left eye plus writing the layers.
    pub left_ms: f64,
    pub composite_ms: f64,
}

/// Both eyes from one ray casting pass.
#[derive(Clone, Debug, PartialEq)]
pub struct StereoFrames {
    pub left: Frame,
    /// Colour only; `depth` is None and `samples` 0 (nothing is sampled).
    pub right: Frame,
    pub times: StereoTimes,
}
