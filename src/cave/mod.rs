//! CAVE rigs: walls, viewer and tracked head, loaded from TOML, turned into
//! one off-axis view per wall and eye for any head pose; and multi-view
//! autostereoscopic displays, whose every subpixel has its own eye.

mod config;
mod display;
mod head;
pub mod inspect;
mod placement;
mod rig;
mod source_map;

pub use config::ConfigError;
pub use head::{pose_along, HeadFrame, HeadPose, PathKey, NECK_TO_EYES_M};
pub use placement::ScenePlacement;
pub use rig::{Eye, Rig, View, Viewer, Wall};
// A display file is read here; its model is geometry.
pub use crate::geometry::{MultiViewDisplay, Units, ViewPattern, MAX_VIEWS};
