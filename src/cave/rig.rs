use std::fmt;

use glam::{DVec3, UVec2};
use serde::{Deserialize, Serialize};

use super::head::{pose_along, HeadFrame, HeadPose, PathKey, NECK_TO_EYES_M};
use super::placement::ScenePlacement;
use crate::geometry::{
    pinhole_from_matrices, MatrixCamera, OffAxisCamera, OffAxisProjection, PinholeCamera,
    RecoveredPinhole, Result, Screen, Units,
};

/// Which eye a view is for. `Mono` is the point midway between the eyes,
/// for walls driven without stereo.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Eye {
    Left,
    Right,
    Mono,
}

impl Eye {
    pub const ALL: [Eye; 3] = [Eye::Left, Eye::Right, Eye::Mono];

    pub fn name(self) -> &'static str {
        match self {
            Eye::Left => "left",
            Eye::Right => "right",
            Eye::Mono => "mono",
        }
    }

    /// Position along the head's right axis in units of ipd / 2.
    fn side(self) -> f64 {
        match self {
            Eye::Left => -1.0,
            Eye::Right => 1.0,
            Eye::Mono => 0.0,
        }
    }
}

impl fmt::Display for Eye {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One projection wall: its corners, the pixels per eye, and which eyes
/// are rendered on it.
#[derive(Clone, Debug, PartialEq)]
pub struct Wall {
    pub name: String,
    pub screen: Screen,
    pub resolution: UVec2,
    pub eyes: Vec<Eye>,
}

/// The person in the rig: eye separation, the rest frame of the head, where
/// the eyes sit relative to the tracked point, and the default head pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Viewer {
    pub ipd: f64,
    pub frame: HeadFrame,
    /// Midpoint between the eyes relative to the tracked head point, as
    /// (right, up, forward) in the head frame.
    pub eye_offset: DVec3,
    pub head: HeadPose,
    /// Box the tracker covers (min, max), if the rig states it.
    pub tracked_space: Option<(DVec3, DVec3)>,
    /// Timed head poses for animations, sorted by time.
    pub path: Vec<PathKey>,
}

/// A display rig: walls, viewer and clip planes, all in `units`.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    pub name: String,
    pub units: Units,
    pub near: f64,
    pub far: f64,
    pub viewer: Viewer,
    /// Where a volume goes unless the user says otherwise.
    pub scene: ScenePlacement,
    pub walls: Vec<Wall>,
}

/// Everything needed to render one eye on one wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub eye: Eye,
    pub eye_position: DVec3,
    pub resolution: UVec2,
    pub camera: OffAxisCamera,
    pub projection: OffAxisProjection,
}

impl View {
    /// Strategy 1: the OpenGL matrices as a host would pass them.
    pub fn matrix_camera(&self) -> Result<MatrixCamera> {
        MatrixCamera::new(self.projection.view, self.projection.proj)
    }
    /// Strategy 2: pinhole at the eye plus image region.
    pub fn pinhole(&self) -> Result<PinholeCamera> {
        PinholeCamera::from_screen(self.camera.screen(), self.eye_position)
    }
    /// Strategy 3: pinhole recovered from the matrices alone.
    pub fn pinhole_from_matrices(&self) -> Result<RecoveredPinhole> {
        pinhole_from_matrices(self.projection.view, self.projection.proj)
    }
}

impl Rig {
    pub fn wall(&self, name: &str) -> Option<&Wall> {
        self.walls
            .iter()
            .find(|w| w.name.eq_ignore_ascii_case(name))
    }

    /// A head pose from a position and yaw/pitch/roll in degrees relative to
    /// the rig's rest frame; omitted parts come from the rig's default pose.
    pub fn head_pose(&self, position: Option<DVec3>, ypr_degrees: Option<DVec3>) -> HeadPose {
        HeadPose {
            position: position.unwrap_or(self.viewer.head.position),
            orientation: ypr_degrees.map_or(self.viewer.head.orientation, |ypr| {
                self.viewer.frame.orientation(ypr)
            }),
        }
    }

    /// This rig with its tracked head point at the neck's pivot: the eyes
    /// [`NECK_TO_EYES_M`] from it.
    pub fn with_neck_model(&self) -> Self {
        let mut rig = self.clone();
        rig.viewer.eye_offset = NECK_TO_EYES_M / self.units.metres_per_unit();
        rig
    }

    /// The head pose `time` seconds along the rig's path, or the default
    /// pose if the rig has no path.
    pub fn head_at(&self, time: f64) -> HeadPose {
        pose_along(&self.viewer.path, time).unwrap_or(self.viewer.head)
    }

    /// Eyes sit at the head's eye point +/- ipd/2 along the head's right axis.
    pub fn eye_position(&self, head: &HeadPose, eye: Eye) -> DVec3 {
        let f = &self.viewer.frame;
        let o = self.viewer.eye_offset;
        let local =
            (o.x + eye.side() * 0.5 * self.viewer.ipd) * f.right + o.y * f.up + o.z * f.forward;
        head.position + head.orientation * local
    }

    /// The view of one eye on one wall; fails if that eye is on or behind
    /// the wall.
    pub fn view(&self, wall: &Wall, eye: Eye, head: &HeadPose) -> Result<View> {
        let eye_position = self.eye_position(head, eye);
        let camera = OffAxisCamera::new(wall.screen, eye_position)?;
        Ok(View {
            eye,
            eye_position,
            resolution: wall.resolution,
            camera,
            projection: camera.projection(self.near, self.far)?,
        })
    }

    /// Every eye of every wall, in file order.
    pub fn views(&self, head: &HeadPose) -> Vec<(&Wall, Eye, Result<View>)> {
        self.walls
            .iter()
            .flat_map(|w| w.eyes.iter().map(move |&e| (w, e, self.view(w, e, head))))
            .collect()
    }
}
