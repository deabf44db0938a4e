//! What a frame's render is made of, as plain values: the device's
//! snapshot of its objects when the frame renders.

use std::sync::Arc;

use glam::{UVec2, Vec2, Vec3};

use crate::cluster::Ranks;

use crate::geometry::{MatrixCamera, MultiViewDisplay, RayGen};
use crate::render::iso::{IsoSurface, MultiViewMethod};
use crate::render::{Backend, FrameDesc, RenderSettings, StreamWait};
use crate::scene::Scene;

/// One eye's rays and the rectangle of the frame they fill.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeView {
    pub rays: RayGen,
    pub offset: UVec2,
    pub size: UVec2,
    /// The eye as OpenGL matrices, where it has them (a stereo pair with
    /// the whole image region): what re-projection plans with.
    pub matrix: Option<MatrixCamera>,
}

/// What a frame's camera shows, and so how its image is made. (Views live
/// in an `Arc<Inputs>`; boxing the eyes would only add an indirection.)
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)]
pub enum Views {
    /// One view of the whole frame.
    Mono(EyeView),
    /// The two eyes of a stereo camera, left then right, each into its
    /// part of the frame: one re-projection pass where that applies.
    StereoPair([EyeView; 2]),
    /// A multi-view panel: every view over the whole frame, interleaved
    /// subpixel by subpixel into one image.
    Panel(PanelViews),
}

#[derive(Clone, Debug, PartialEq)]
pub struct PanelViews {
    pub views: Vec<EyeView>,
    /// Which view each subpixel shows.
    pub display: Arc<MultiViewDisplay>,
    pub method: MultiViewMethod,
}

impl Views {
    /// These views through points `by` pixels off their pixels' centres,
    /// without their matrices (which describe the centred rays).
    pub fn shifted(&self, by: Vec2) -> Views {
        let shift = |v: &EyeView| EyeView {
            rays: v.rays.shifted(by),
            matrix: None,
            ..*v
        };
        match self {
            Views::Mono(one) => Views::Mono(shift(one)),
            Views::StereoPair(pair) => Views::StereoPair(pair.each_ref().map(shift)),
            Views::Panel(panel) => Views::Panel(PanelViews {
                views: panel.views.iter().map(shift).collect(),
                ..panel.clone()
            }),
        }
    }

    /// Every view, in order.
    pub fn all(&self) -> &[EyeView] {
        match self {
            Views::Mono(one) => std::slice::from_ref(one),
            Views::StereoPair(pair) => pair,
            Views::Panel(panel) => &panel.views,
        }
    }
}

/// Everything a frame's render depends on, copied out of the committed
/// objects so the host may change them while the frame renders. Equal
/// inputs make the same image: the scene and the surfaces compare by
/// identity (a commit makes new derived values, so any change makes new
/// ones), everything else by value.
#[derive(Clone)]
pub struct Inputs {
    /// The world's volumes; `None` with no `surfaces` renders the
    /// background only (an empty world).
    pub scene: Option<Scene>,
    /// The world's isosurfaces (a world holds volumes or surfaces).
    pub surfaces: Vec<IsoSurface>,
    pub views: Views,
    pub settings: RenderSettings,
    pub desc: FrameDesc,
    pub backend: Backend,
    /// Bytes of volume textures the GPU may hold (the device's
    /// `caveray.memoryBudget`); None: what the driver allows.
    pub gpu_budget: Option<u64>,
    /// How long a GPU frame waits for the bricks of paged volumes (the
    /// device's `caveray.streamWait`).
    pub stream_wait: StreamWait,
    /// The host set the frame's `accumulation`: renders of unchanged
    /// inputs refine the image (src/engine/accumulation.rs).
    pub accumulate: bool,
    /// Under the device's `caveray.mpi`: this rank's share of a
    /// data-parallel frame (src/engine/data_parallel.rs).
    pub share: Option<Share>,
}

/// A rank's share of a data-parallel frame: the job's ranks and the box of
/// world space this rank's world owns.
#[derive(Clone)]
pub struct Share {
    pub ranks: Arc<Ranks>,
    pub region: (Vec3, Vec3),
}

impl PartialEq for Share {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.ranks, &other.ranks) && self.region == other.region
    }
}

impl PartialEq for Inputs {
    fn eq(&self, other: &Self) -> bool {
        let same_scene = match (&self.scene, &other.scene) {
            (None, None) => true,
            (Some(a), Some(b)) => a.same(b),
            _ => false,
        };
        same_scene
            && self.surfaces.len() == other.surfaces.len()
            && self
                .surfaces
                .iter()
                .zip(&other.surfaces)
                .all(|(a, b)| a.same(b))
            && self.views == other.views
            && self.settings == other.settings
            && self.desc == other.desc
            && self.backend == other.backend
            && self.gpu_budget == other.gpu_budget
            && self.stream_wait == other.stream_wait
            && self.accumulate == other.accumulate
            && self.share == other.share
    }
}

/// Why inputs cannot be rendered as one image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unrenderable {
    /// Volumes and isosurfaces in one world.
    VolumesAndSurfaces,
    /// A panel image asked for depth.
    PanelDepth,
    /// A panel image asked for hit channels.
    PanelHits,
    /// A world of isosurfaces asked for hit channels.
    IsosurfaceHits,
    /// A panel image of more than one isosurface (how many).
    PanelSurfaces(usize),
}

impl Inputs {
    /// Whether the renderers can make one image of these inputs.
    pub fn check(&self) -> Result<(), Unrenderable> {
        if self.scene.is_some() && !self.surfaces.is_empty() {
            return Err(Unrenderable::VolumesAndSurfaces);
        }
        if self.desc.hits && !self.surfaces.is_empty() {
            return Err(Unrenderable::IsosurfaceHits);
        }
        if let Views::Panel(_) = self.views {
            if self.desc.depth {
                return Err(Unrenderable::PanelDepth);
            }
            if self.desc.hits {
                return Err(Unrenderable::PanelHits);
            }
            if self.surfaces.len() > 1 {
                return Err(Unrenderable::PanelSurfaces(self.surfaces.len()));
            }
        }
        Ok(())
    }
}
