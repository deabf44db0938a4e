//! The length unit of a rig's or a display's coordinates.

use serde::{Deserialize, Serialize};

/// Length unit of every coordinate in a rig or display file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
pub enum Units {
    #[serde(rename = "mm")]
    Millimetres,
    #[serde(rename = "m")]
    Metres,
}

impl Units {
    pub fn metres_per_unit(self) -> f64 {
        match self {
            Units::Millimetres => 1e-3,
            Units::Metres => 1.0,
        }
    }
    pub fn symbol(self) -> &'static str {
        match self {
            Units::Millimetres => "mm",
            Units::Metres => "m",
        }
    }
}
