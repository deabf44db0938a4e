//! Which way up published data sets are, for raw files that cannot say:
//! found by the SHA-256 a manifest gives for the file, so a renamed copy is
//! still known and an edited one is not.

use crate::geometry::VolumeAxis;

/// A data set's up and front axes (`front`: the side its face is on).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Orientation {
    pub up: Option<VolumeAxis>,
    pub front: Option<VolumeAxis>,
}

impl Orientation {
    pub const UNKNOWN: Orientation = Orientation {
        up: None,
        front: None,
    };
}

/// (SHA-256, up, front). Both heads are axial CT series stored crown
/// first, the face toward the first rows: the Stanford CT head (the CT
/// table lies at its last rows, under the back of the head) and VTK's
/// headsq, which VTK's own examples view with up -z from -y.
const KNOWN: &[(&str, VolumeAxis, VolumeAxis)] = &[
    (
        "8a378356d37fc55a977032375b1bd34298c0b137167dd0f05e025d66e0ae5d94",
        VolumeAxis::NegZ,
        VolumeAxis::NegY,
    ),
    (
        "74011a3339b1a56ca85c8c6920a46c0f80bddcc660bd9f78512888e06c496ce3",
        VolumeAxis::NegZ,
        VolumeAxis::NegY,
    ),
];

/// The orientation of the data set whose file has this SHA-256 (hex, any
/// case), if it is one of the known ones.
pub fn known_orientation(sha256: &str) -> Orientation {
    KNOWN
        .iter()
        .find(|(sha, _, _)| sha.eq_ignore_ascii_case(sha256.trim()))
        .map_or(Orientation::UNKNOWN, |&(_, up, front)| Orientation {
            up: Some(up),
            front: Some(front),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ct_head_is_known_by_its_hash_in_any_case() {
        let o =
            known_orientation("8A378356D37FC55A977032375B1BD34298C0B137167DD0F05E025D66E0AE5D94");
        assert_eq!(o.up, Some(VolumeAxis::NegZ));
        assert_eq!(o.front, Some(VolumeAxis::NegY));
        assert_eq!(known_orientation("00"), Orientation::UNKNOWN);
    }
}
