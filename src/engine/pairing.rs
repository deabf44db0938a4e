//! Per-eye stereo pairing: a frame whose camera shows one eye of a wall
//! is rendered with the frame showing the other eye in one re-projection
//! pass, and that frame's image is kept for its next render. Whether two
//! frames pair is decided here from their inputs; which frames are
//! candidates (a named `stereoPartner`, or any frame of the device) is
//! the device's matter.

use std::sync::Arc;

use super::inputs::{EyeView, Inputs, Views};
use super::job::{FrameRenders, Partner, RenderJob};
use super::passes::REPROJECTION_LAYERS;
use crate::geometry::{MatrixCamera, PrimaryRays};
use crate::render::stereo::{decide, Bounds, Eyes};
use crate::scene::Scene;

/// Why a frame is not a job's partner.
#[derive(Clone)]
pub enum Unpaired {
    /// It cannot be: the host should hear why if it named it.
    Unsuited(String),
    /// Pairing would gain nothing: it already has its image.
    Pointless,
}

fn unsuited(why: &str) -> Unpaired {
    Unpaired::Unsuited(why.to_owned())
}

/// The eye of the job looking for a partner.
pub struct OwnEye<'a> {
    job: &'a RenderJob,
    scene: &'a Scene,
    matrix: MatrixCamera,
}

impl<'a> OwnEye<'a> {
    /// The job's one perspective view of a scene, which a partner could
    /// complete.
    pub fn of(job: &'a RenderJob) -> Result<Self, Unpaired> {
        let (Views::Mono(view), Some(scene)) = (&job.inputs.views, &job.inputs.scene) else {
            return Err(Unpaired::Pointless);
        };
        let matrix = view.matrix.ok_or_else(|| {
            unsuited("is paired with a frame whose camera is not a perspective one")
        })?;
        Ok(Self { job, scene, matrix })
    }

    /// Frame `frame`, whose render would be of `theirs` and which keeps
    /// `renders`, as the job's partner, with the eyes' distance: the same
    /// world, renderer, size and channels, one eye a small baseline away
    /// on the same image plane, and an image not made yet.
    pub fn with(
        &self,
        frame: u64,
        theirs: &Arc<Inputs>,
        renders: &FrameRenders,
    ) -> Result<(f64, Partner), Unpaired> {
        let own = &self.job.inputs;
        if !theirs.scene.as_ref().is_some_and(|s| s.same(self.scene)) {
            return Err(unsuited("shows another world"));
        }
        if theirs.settings != own.settings || theirs.backend != own.backend {
            return Err(unsuited("has another renderer"));
        }
        if theirs.desc != own.desc {
            return Err(unsuited("differs in size or channels"));
        }
        let other: &EyeView = match &theirs.views {
            Views::Panel(_) => return Err(unsuited("renders a multi-view panel")),
            Views::StereoPair(_) => return Err(unsuited("renders both eyes itself (stereoMode)")),
            Views::Mono(other) => other,
        };
        let matrix = other
            .matrix
            .ok_or_else(|| unsuited("has a camera that is not a perspective one"))?;
        let (Some(a), Some(b)) = (self.matrix.eye(), matrix.eye()) else {
            return Err(unsuited("has a camera that is not a perspective one"));
        };
        let (lo, hi) = self.scene.bounds();
        let distance = (0.5 * (lo + hi)).as_dvec3().distance(a);
        let baseline = a.distance(b);
        if baseline == 0.0 {
            return Err(unsuited("sees from the same eye"));
        }
        if baseline > 0.25 * distance {
            return Err(Unpaired::Unsuited(format!(
                "has its eye {baseline:.4} away, more than a quarter of the distance to the volume ({distance:.4})"
            )));
        }
        if renders.has_image_of(theirs) {
            return Err(Unpaired::Pointless);
        }
        // The renderer is the render thread's, not known yet: it admits
        // the plan when the pair renders.
        let eyes = Eyes {
            left: Ok(self.matrix),
            right: Ok(matrix),
            sizes: [own.desc.size; 2],
        };
        let plan = decide(eyes, Bounds::of(self.scene), REPROJECTION_LAYERS, None)
            .map_err(|e| Unpaired::Unsuited(format!("cannot be re-projected: {e}")))?;
        Ok((
            baseline,
            Partner {
                frame,
                view: *other,
                slot: Arc::clone(&renders.slot),
                inputs: Arc::clone(theirs),
                plan,
            },
        ))
    }
}
