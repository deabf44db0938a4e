//! CAVE rigs: walls, viewer and tracked head, loaded from TOML, turned into
//! one off-axis view per wall and eye for any head pose.

mod config;
mod head;
pub mod inspect;
mod rig;
mod source_map;

pub use config::ConfigError;
pub use head::{pose_along, HeadFrame, HeadPose, PathKey, NECK_TO_EYES_M};
pub use rig::{Eye, Rig, ScenePlacement, Units, View, Viewer, Wall};
