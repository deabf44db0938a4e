//! The re-projection planner for Buchacher & Erdt's HMD-style setup: two
//! coplanar image planes at focal length h, eyes e apart, a volume inside
//! a bounding sphere of radius r whose near side touches the image plane.
//!
//! A left ray re-projects onto a segment of the right eye's epipolar line;
//! its longest such segment, in pixels, is the number of layers needed so
//! that no two left rays write the same texel of the same layer.

use glam::UVec2;
use thiserror::Error;

use super::layers::{layer_count, layer_memory, layers_for, LayerCountError, LayerFormat};

#[derive(Debug, Error, PartialEq)]
pub enum StereoError {
    #[error("{what} must be finite and positive, got {value}")]
    NotPositive { what: &'static str, value: f64 },
    #[error("eye distance must be finite and not negative, got {0}")]
    NegativeEyeDistance(f64),
    #[error("field of view must be in (0, 180) degrees, got {0} degrees")]
    FieldOfView(f64),
    #[error(transparent)]
    Layers(#[from] LayerCountError),
}

/// Buchacher & Erdt's protocol (docs/reprojection_stereo.md): image width and
/// height, full horizontal field of view, eye distance, bounding radius of
/// the volume, re-projection layers, largest re-projected span (which
/// fixes the focal length), and views in the 360 degree turn about y.
pub mod paper {
    pub const WIDTH: u32 = 768;
    pub const FOV_DEGREES: f64 = 110.0;
    pub const EYE_DISTANCE_M: f64 = 0.065;
    pub const RADIUS_M: f64 = 1.0;
    pub const LAYERS: u32 = 32;
    pub const SPAN_PX: f64 = 32.0;
    pub const VIEWS: u32 = 50;
}

/// Pixels per image-plane unit: `s = w / (2 h tan a)`.
pub fn pixel_scale(width: f64, focal: f64, half_fov: f64) -> f64 {
    width / (2.0 * focal * half_fov.tan())
}

/// Epipolar segment of a ray from the image plane to infinity: `d_inf = e`.
pub fn span_to_infinity(eye_distance: f64) -> f64 {
    eye_distance
}

/// ... from the image plane to depth `z`: `d_z = e - e h / z`.
pub fn span_to_depth(eye_distance: f64, focal: f64, z: f64) -> f64 {
    eye_distance - eye_distance * focal / z
}

/// ... through a bounding sphere of radius `r` whose near side touches the
/// image plane: `d_r = e - e h / (h + 2r)`.
pub fn span_to_sphere(eye_distance: f64, focal: f64, radius: f64) -> f64 {
    span_to_depth(eye_distance, focal, focal + 2.0 * radius)
}

/// The shortest focal length at which a sphere of radius `r` re-projects
/// onto at most `span_px` pixels: `h = -r + sqrt(r^2 + e r w / (d_p tan a))`.
pub fn minimal_focal_length(
    radius: f64,
    eye_distance: f64,
    width: f64,
    span_px: f64,
    half_fov: f64,
) -> f64 {
    -radius + (radius * radius + eye_distance * radius * width / (span_px * half_fov.tan())).sqrt()
}

/// Buchacher & Erdt's setup, in metres and radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HmdStereo {
    /// Image width (and height) in pixels.
    pub width: u32,
    /// Full horizontal field of view 2a.
    pub fov: f64,
    pub eye_distance: f64,
    /// Distance h from the eyes to the image plane.
    pub focal: f64,
    /// Bounding sphere radius r; `None` plans for rays to infinity.
    pub radius: Option<f64>,
}

/// How many layers a view needs and what they cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerPlan {
    /// Longest re-projected span d_p in pixels.
    pub span_px: f64,
    /// Layers needed: every pixel a span touches gets its own layer.
    pub layers: u32,
    /// Bytes of that many RGBA16F layers.
    pub memory: u64,
}

impl HmdStereo {
    /// Buchacher & Erdt's protocol with the shortest focal length that `layers`
    /// layers allow: a span of `layers - 1` pixels.
    pub fn paper_for_layers(layers: u32) -> Self {
        Self::paper(f64::from(layers.max(2) - 1))
    }

    /// Buchacher & Erdt's protocol: 768^2, 2a = 110 degrees, e = 0.065 m, r = 1 m,
    /// and the focal length at which the sphere spans `span_px` pixels.
    pub fn paper(span_px: f64) -> Self {
        Self::protocol(paper::WIDTH, span_px)
    }

    /// Buchacher & Erdt's protocol at another image width.
    pub fn protocol(width: u32, span_px: f64) -> Self {
        let (fov, e, r) = (
            paper::FOV_DEGREES.to_radians(),
            paper::EYE_DISTANCE_M,
            paper::RADIUS_M,
        );
        Self {
            width,
            fov,
            eye_distance: e,
            focal: minimal_focal_length(r, e, f64::from(width), span_px, 0.5 * fov),
            radius: Some(r),
        }
    }

    fn check(&self) -> Result<(), StereoError> {
        let positive = |what, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(StereoError::NotPositive { what, value })
            }
        };
        positive("image width", f64::from(self.width))?;
        positive("focal length", self.focal)?;
        if let Some(r) = self.radius {
            positive("bounding radius", r)?;
        }
        if !(self.eye_distance.is_finite() && self.eye_distance >= 0.0) {
            return Err(StereoError::NegativeEyeDistance(self.eye_distance));
        }
        if !(self.fov > 0.0 && self.fov < std::f64::consts::PI) {
            return Err(StereoError::FieldOfView(self.fov.to_degrees()));
        }
        Ok(())
    }

    /// The longest span and the layers it needs.
    pub fn plan(&self) -> Result<LayerPlan, StereoError> {
        self.check()?;
        let span = match self.radius {
            Some(r) => span_to_sphere(self.eye_distance, self.focal, r),
            None => span_to_infinity(self.eye_distance),
        };
        let span_px = span * pixel_scale(f64::from(self.width), self.focal, 0.5 * self.fov);
        let layers = layers_for(span_px);
        Ok(LayerPlan {
            span_px,
            layers,
            memory: layer_memory(UVec2::splat(self.width), layers, LayerFormat::Rgba16F),
        })
    }

    /// The plan, held to a given layer count: too few layers is an error
    /// naming how many are needed.
    pub fn plan_with(&self, layers: u32) -> Result<LayerPlan, StereoError> {
        if layers == 0 {
            return Err(LayerCountError::NoLayers.into());
        }
        let needed = self.plan()?;
        let layers = layer_count(Some(layers), needed.layers, || {
            format!("a span of {:.2} pixels", needed.span_px)
        })?;
        Ok(LayerPlan {
            layers,
            memory: layer_memory(UVec2::splat(self.width), layers, LayerFormat::Rgba16F),
            ..needed
        })
    }
}
