//! What the GPU's re-projection path needs from the planner: the right
//! eye's pixel as a function of a world point, the epipolar plan, the
//! layer count and format; and what it gives back.

use glam::{DVec4, UVec2, Vec3, Vec4};
use thiserror::Error;

use super::bounds::Bounds;
use super::epipolar::{plan_views, NotEpipolar, ViewPlan};
use super::layers::{layer_count, LayerCountError, LayerFormat};
use crate::geometry::{MatrixCamera, PrimaryRays, RayGen};
use crate::render::Frame;

/// Layer memory a plan may ask for: beyond it the two passes are the
/// better use of the GPU.
pub const LAYER_BUDGET: u64 = 1 << 30;

/// Why a view pair renders in two passes instead.
#[derive(Debug, Error, PartialEq)]
pub enum ReprojectionError {
    #[error("re-projection does not apply: {0}")]
    NotEpipolar(#[from] NotEpipolar),
    #[error(transparent)]
    Layers(#[from] LayerCountError),
    #[error("image must be at least 1x1, got {}x{}", .0.x, .0.y)]
    EmptyImage(UVec2),
    #[error("the layers would take {} MiB ({layers} layers of {}x{}, {families} famil{}), over the {} MiB budget", .bytes >> 20, .texels.x, .texels.y, if *.families == 1 { "y" } else { "ies" }, LAYER_BUDGET >> 20)]
    OverBudget {
        bytes: u64,
        layers: u32,
        families: u32,
        texels: UVec2,
    },
    #[error("the left eye would cast {}x{} rays for a {}x{} image, more than both eyes cast in two passes (the volume reaches too close to the eyes)", .cast.x, .cast.y, .size.x, .size.y)]
    Costlier { cast: UVec2, size: UVec2 },
}

/// A planned re-projection of the left eye's rays into the right eye.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reprojection {
    pub size: UVec2,
    pub plan: ViewPlan,
    /// Layers of each family: the plan's, or more if asked for.
    pub layers: u32,
    pub format: LayerFormat,
    /// Right-eye pixel (x, y) of world point p is
    /// `(right_x, right_y) . (p, 1) / right_w . (p, 1)`.
    pub right_x: Vec4,
    pub right_y: Vec4,
    pub right_w: Vec4,
    /// Where right-eye depth is measured from.
    pub right_eye: Vec3,
    /// The right eye's rays, for what the right eye ray traces itself.
    pub right_rays: RayGen,
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
        let pixels = |s: UVec2| u64::from(s.x) * u64::from(s.y);
        if pixels(plan.cast) > 2 * pixels(size) {
            return Err(ReprojectionError::Costlier {
                cast: plan.cast,
                size,
            });
        }
        let layers = layer_count(layers, plan.layers, || {
            format!("{:.1} pixels along one ray", plan.span_px)
        })?;
        let bytes = plan.memory(layers, format);
        if bytes > LAYER_BUDGET {
            return Err(ReprojectionError::OverBudget {
                bytes,
                layers,
                families: plan.family_count(),
                texels: plan.texture_size(),
            });
        }
        let m = right.proj() * right.view();
        let (row_x, row_y, row_w) = (m.row(0), m.row(1), m.row(3));
        // NDC in [-1, 1] to pixels with centres on whole numbers.
        let to_pixel = |row: DVec4, n: u32| -> Vec4 {
            (0.5 * f64::from(n) * (row + row_w) - 0.5 * row_w).as_vec4()
        };
        let right_eye = right.eye().unwrap_or_default().as_vec3();
        Ok(Self {
            size,
            plan,
            layers,
            format,
            right_x: to_pixel(row_x, size.x),
            right_y: to_pixel(row_y, size.y),
            right_w: row_w.as_vec4(),
            right_eye,
            right_rays: right.ray_gen(size),
        })
    }

    /// Bytes of the layers.
    pub fn memory(&self) -> u64 {
        self.plan.memory(self.layers, self.format)
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
    /// Depth as the frame asked; `samples` 0 (nothing is sampled).
    pub right: Frame,
    pub times: StereoTimes,
}
