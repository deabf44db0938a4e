//! The one decision whether a stereo pair is rendered in one
//! re-projection pass or in two passes, for every caller: the device's
//! stereo cameras and per-eye frames, `caveray render` and both stereo
//! benchmarks. It returns the plan it made, which the pass then runs, or
//! why the pair takes two passes.

use glam::UVec2;
use thiserror::Error;

use super::bounds::Bounds;
use super::layers::LayerFormat;
use super::reproject::{Reprojection, ReprojectionError};
use crate::geometry::MatrixCamera;

/// The two eyes as the decision takes them.
#[derive(Clone, Debug)]
pub struct Eyes {
    /// Each eye's matrices, or (in the caller's words) why it has none.
    pub left: Result<MatrixCamera, String>,
    pub right: Result<MatrixCamera, String>,
    /// Each eye's image size, left then right.
    pub sizes: [UVec2; 2],
}

/// The layers asked for: `count: None` takes the planned count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerRequest {
    pub count: Option<u32>,
    pub format: LayerFormat,
}

/// What the renderer that would run the pass brings to the decision.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderFacts {
    /// The renderer has the re-projection pass (the GPU renderer).
    pub reprojects: bool,
    /// The frame's background is an image; the pass composites over a
    /// color only.
    pub background_image: bool,
    /// The frame asks for hit channels, which the right eye's composite
    /// does not fill.
    pub hits: bool,
}

/// Why a pair is rendered in two passes.
#[derive(Debug, Error, PartialEq)]
pub enum TwoPasses {
    #[error("re-projection runs on the GPU renderer only")]
    NotOnThisRenderer,
    #[error("{0}")]
    NoMatrices(String),
    #[error("the eyes differ in size ({}x{} and {}x{}); give the frame an even split", .0.x, .0.y, .1.x, .1.y)]
    UnevenEyes(UVec2, UVec2),
    #[error("re-projection takes a background color, not an image")]
    BackgroundImage,
    #[error("the right eye is composited with color and depth only; a frame asking for id, normal or albedo channels renders each eye in its own pass")]
    HitChannels,
    #[error(transparent)]
    Plan(#[from] ReprojectionError),
}

impl RenderFacts {
    /// Whether this renderer may run a pair planned without knowing it.
    pub fn admit(&self) -> Result<(), TwoPasses> {
        if !self.reprojects {
            return Err(TwoPasses::NotOnThisRenderer);
        }
        if self.background_image {
            return Err(TwoPasses::BackgroundImage);
        }
        if self.hits {
            return Err(TwoPasses::HitChannels);
        }
        Ok(())
    }
}

/// The pair's re-projection plan for a scene inside `bounds`, or why the
/// pair takes two passes. `facts: None` plans before the renderer is
/// known; [`RenderFacts::admit`] then checks the plan against it. The
/// checks run in a fixed order, so a pair that fails several gives the
/// same reason wherever it is decided.
pub fn decide(
    eyes: Eyes,
    bounds: Bounds,
    layers: LayerRequest,
    facts: Option<RenderFacts>,
) -> Result<Reprojection, TwoPasses> {
    if facts.is_some_and(|f| !f.reprojects) {
        return Err(TwoPasses::NotOnThisRenderer);
    }
    let left = eyes.left.map_err(TwoPasses::NoMatrices)?;
    let right = eyes.right.map_err(TwoPasses::NoMatrices)?;
    let [left_size, right_size] = eyes.sizes;
    if left_size != right_size {
        return Err(TwoPasses::UnevenEyes(left_size, right_size));
    }
    if facts.is_some_and(|f| f.background_image) {
        return Err(TwoPasses::BackgroundImage);
    }
    if facts.is_some_and(|f| f.hits) {
        return Err(TwoPasses::HitChannels);
    }
    Ok(Reprojection::new(
        &left,
        &right,
        left_size,
        bounds,
        layers.count,
        layers.format,
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::stereo::HmdStereo;
    use glam::DVec3;

    const SIZE: u32 = 48;

    fn eyes() -> Eyes {
        let (left, right) = HmdStereo::protocol(SIZE, 7.0).eyes(0.3).unwrap();
        Eyes {
            left: Ok(left),
            right: Ok(right),
            sizes: [UVec2::splat(SIZE); 2],
        }
    }

    const LAYERS: LayerRequest = LayerRequest {
        count: None,
        format: LayerFormat::Rgba16F,
    };

    fn bounds() -> Bounds {
        Bounds::Sphere {
            centre: DVec3::ZERO,
            radius: 1.0,
        }
    }

    #[test]
    fn a_plan_made_before_the_renderer_is_known_is_the_same_plan() {
        let facts = RenderFacts {
            reprojects: true,
            background_image: false,
            hits: false,
        };
        let early = decide(eyes(), bounds(), LAYERS, None).unwrap();
        facts.admit().unwrap();
        assert_eq!(
            early,
            decide(eyes(), bounds(), LAYERS, Some(facts)).unwrap()
        );
    }

    #[test]
    fn the_reasons_come_in_one_order() {
        let cpu = RenderFacts {
            reprojects: false,
            background_image: true,
            hits: false,
        };
        let no_matrices = Eyes {
            left: Err("no matrices".into()),
            ..eyes()
        };
        assert_eq!(
            decide(no_matrices.clone(), bounds(), LAYERS, Some(cpu)),
            Err(TwoPasses::NotOnThisRenderer)
        );
        let gpu_over_image = RenderFacts {
            reprojects: true,
            background_image: true,
            hits: false,
        };
        assert_eq!(
            decide(no_matrices, bounds(), LAYERS, Some(gpu_over_image)),
            Err(TwoPasses::NoMatrices("no matrices".into()))
        );
        let uneven = Eyes {
            sizes: [UVec2::new(31, 32), UVec2::new(33, 32)],
            ..eyes()
        };
        assert!(matches!(
            decide(uneven, bounds(), LAYERS, Some(gpu_over_image)),
            Err(TwoPasses::UnevenEyes(..))
        ));
        assert_eq!(
            decide(eyes(), bounds(), LAYERS, Some(gpu_over_image)),
            Err(TwoPasses::BackgroundImage)
        );
        assert_eq!(gpu_over_image.admit(), Err(TwoPasses::BackgroundImage));
        assert_eq!(cpu.admit(), Err(TwoPasses::NotOnThisRenderer));
        let with_hits = RenderFacts {
            reprojects: true,
            background_image: false,
            hits: true,
        };
        let err = decide(eyes(), bounds(), LAYERS, Some(with_hits)).unwrap_err();
        assert_eq!(err, TwoPasses::HitChannels);
        assert!(err.to_string().contains("each eye in its own pass"));
    }
}
