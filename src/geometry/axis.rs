//! The six axis directions of a volume grid, by name.

use std::fmt;
use std::str::FromStr;

use glam::DVec3;
use serde::{Deserialize, Deserializer};

/// One of a volume grid's six axis directions (`+x` is the direction of
/// increasing first index).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeAxis {
    PosX,
    NegX,
    PosY,
    NegY,
    PosZ,
    NegZ,
}

impl VolumeAxis {
    pub const NAMES: [&'static str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];

    pub fn vector(self) -> DVec3 {
        match self {
            VolumeAxis::PosX => DVec3::X,
            VolumeAxis::NegX => DVec3::NEG_X,
            VolumeAxis::PosY => DVec3::Y,
            VolumeAxis::NegY => DVec3::NEG_Y,
            VolumeAxis::PosZ => DVec3::Z,
            VolumeAxis::NegZ => DVec3::NEG_Z,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            VolumeAxis::PosX => "+x",
            VolumeAxis::NegX => "-x",
            VolumeAxis::PosY => "+y",
            VolumeAxis::NegY => "-y",
            VolumeAxis::PosZ => "+z",
            VolumeAxis::NegZ => "-z",
        }
    }
}

impl fmt::Display for VolumeAxis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for VolumeAxis {
    type Err = String;

    /// `+x`, `x`, `-x`, ... in any case.
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim().to_ascii_lowercase();
        let (negative, axis) = match t.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, t.strip_prefix('+').unwrap_or(&t)),
        };
        Ok(match (axis, negative) {
            ("x", false) => VolumeAxis::PosX,
            ("x", true) => VolumeAxis::NegX,
            ("y", false) => VolumeAxis::PosY,
            ("y", true) => VolumeAxis::NegY,
            ("z", false) => VolumeAxis::PosZ,
            ("z", true) => VolumeAxis::NegZ,
            _ => {
                return Err(format!(
                    "expected a volume axis ({}), got '{s}'",
                    Self::NAMES.join(", ")
                ))
            }
        })
    }
}

/// Read by name, as `FromStr` reads it (data manifests name axes).
impl<'de> Deserialize<'de> for VolumeAxis {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_parse_with_or_without_sign_in_any_case() {
        assert_eq!("z".parse::<VolumeAxis>(), Ok(VolumeAxis::PosZ));
        assert_eq!("+Y".parse::<VolumeAxis>(), Ok(VolumeAxis::PosY));
        assert_eq!(" -x ".parse::<VolumeAxis>(), Ok(VolumeAxis::NegX));
        let e = "up".parse::<VolumeAxis>().unwrap_err();
        assert!(
            e.contains("+x, -x, +y, -y, +z, -z") && e.contains("'up'"),
            "{e}"
        );
        for name in VolumeAxis::NAMES {
            assert_eq!(name.parse::<VolumeAxis>().unwrap().name(), name);
        }
    }
}
