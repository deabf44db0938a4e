//! Where a rig puts a volume and which way up: the centre and size of its
//! bounding box, and which of the volume's own axes point up and toward
//! the viewer.

use glam::{DMat3, DMat4, DQuat, DVec3};

use super::head::HeadFrame;
use crate::geometry::{Units, VolumeAxis};

/// Where a rig puts the volume: its bounding box is centred at `centre`
/// and its longest side is `size` long, in rig units, unless `life_size`
/// names the data's unit: then the volume is shown at its own size, its
/// file's unit converted to the rig's (`life_size` for data whose file
/// does not say). `up` is the volume axis that points along the viewer's
/// up and `front` the one that faces a viewer at rest (against the
/// viewer's forward); unset, the volume's axes are the rig's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScenePlacement {
    pub centre: DVec3,
    pub size: f64,
    pub life_size: Option<Units>,
    pub up: Option<VolumeAxis>,
    pub front: Option<VolumeAxis>,
}

impl ScenePlacement {
    /// The default: the centre of the box around the walls' `corners`, a
    /// third of its smallest non-zero side (a single flat wall has one zero
    /// side), the volume's axes the rig's.
    pub fn around(corners: impl Iterator<Item = DVec3>) -> Self {
        let (lo, hi) = corners.fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), c| (lo.min(c), hi.max(c)),
        );
        let extent = hi - lo;
        let sides = extent.to_array();
        let smallest = sides
            .iter()
            .copied()
            .filter(|&s| s > 1e-9 * extent.max_element())
            .fold(f64::INFINITY, f64::min);
        Self {
            centre: 0.5 * (lo + hi),
            size: smallest / 3.0,
            life_size: None,
            up: None,
            front: None,
        }
    }

    /// How long the longest side of a volume whose box's longest side is
    /// `extent` (in its data's unit) is shown, in `world` units: `size`,
    /// or its own length where `life_size` says so, in the unit its file
    /// states (`stated_metres`, metres a data unit) or else `life_size`.
    pub fn shown_size(&self, extent: f64, stated_metres: Option<f64>, world: Units) -> f64 {
        match self.life_size {
            None => self.size,
            Some(data) => {
                extent * stated_metres.unwrap_or(data.metres_per_unit()) / world.metres_per_unit()
            }
        }
    }

    /// Why `up` and `front` cannot both hold, if they cannot.
    pub fn check_axes(up: Option<VolumeAxis>, front: Option<VolumeAxis>) -> Result<(), String> {
        match (up, front) {
            (Some(u), Some(f)) if u.vector().dot(f.vector()) != 0.0 => Err(format!(
                "the volume's up axis {u} and front axis {f} must be different axes"
            )),
            _ => Ok(()),
        }
    }

    /// The rotation from the volume's axes to the world's for a viewer
    /// whose rest frame is `frame`. With only one axis given, the smallest
    /// turn that sets it; a half turn keeps the other one where it was
    /// (about the forward axis for `up`, about up for `front`).
    pub fn rotation(&self, frame: &HeadFrame) -> DQuat {
        let toward_viewer = -frame.forward;
        let arc = |from: DVec3, to: DVec3, half_turn_axis: DVec3| {
            if from.dot(to) < -1.0 + 1e-12 {
                DQuat::from_axis_angle(half_turn_axis, std::f64::consts::PI)
            } else {
                DQuat::from_rotation_arc(from, to)
            }
        };
        match (self.up, self.front) {
            (None, None) => DQuat::IDENTITY,
            (Some(u), None) => arc(u.vector(), frame.up, frame.forward),
            (None, Some(f)) => arc(f.vector(), toward_viewer, frame.up),
            (Some(u), Some(f)) => {
                let (u, f) = (u.vector(), f.vector());
                let from = DMat3::from_cols(u, f, u.cross(f));
                let to = DMat3::from_cols(frame.up, toward_viewer, frame.up.cross(toward_viewer));
                // Both bases are orthonormal, so the inverse is the transpose.
                DQuat::from_mat3(&(to * from.transpose()))
            }
        }
    }

    /// Object to world for a volume already centred at `centre`: the
    /// rotation about that centre.
    pub fn transform(&self, frame: &HeadFrame) -> DMat4 {
        DMat4::from_translation(self.centre)
            * DMat4::from_quat(self.rotation(frame))
            * DMat4::from_translation(-self.centre)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn z_up() -> HeadFrame {
        HeadFrame::new(DVec3::Y, DVec3::Z).unwrap()
    }

    fn placement(up: Option<&str>, front: Option<&str>) -> ScenePlacement {
        ScenePlacement {
            centre: DVec3::new(0.0, 850.0, -250.0),
            size: 1300.0,
            life_size: None,
            up: up.map(|s| s.parse().unwrap()),
            front: front.map(|s| s.parse().unwrap()),
        }
    }

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-12
    }

    #[test]
    fn no_axes_leave_the_volume_as_it_is() {
        assert_eq!(placement(None, None).rotation(&z_up()), DQuat::IDENTITY);
    }

    #[test]
    fn a_volume_upside_down_is_turned_about_the_forward_axis() {
        let r = placement(Some("-z"), None).rotation(&z_up());
        assert!(close(r * DVec3::NEG_Z, DVec3::Z));
        // What faced the viewer still does.
        assert!(close(r * DVec3::NEG_Y, DVec3::NEG_Y));
    }

    #[test]
    fn up_and_front_set_the_whole_turn() {
        let frame = HeadFrame::new(DVec3::NEG_Z, DVec3::Y).unwrap();
        let r = placement(Some("-z"), Some("+x")).rotation(&frame);
        assert!(close(r * DVec3::NEG_Z, DVec3::Y));
        assert!(close(r * DVec3::X, DVec3::Z));
        // A turn, not a mirror.
        assert!((DMat3::from_quat(r).determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn front_alone_turns_about_up() {
        let r = placement(None, Some("+y")).rotation(&z_up());
        assert!(close(r * DVec3::Y, DVec3::NEG_Y));
        assert!(close(r * DVec3::Z, DVec3::Z));
    }

    #[test]
    fn the_turn_is_about_the_centre() {
        let p = placement(Some("-z"), Some("-y"));
        let m = p.transform(&z_up());
        assert!(close(m.transform_point3(p.centre), p.centre));
        let top = p.centre + DVec3::new(0.0, 0.0, -100.0);
        assert!(close(
            m.transform_point3(top),
            p.centre + DVec3::new(0.0, 0.0, 100.0)
        ));
    }

    #[test]
    fn up_and_front_on_one_axis_are_refused() {
        let e =
            ScenePlacement::check_axes(Some(VolumeAxis::PosZ), Some(VolumeAxis::NegZ)).unwrap_err();
        assert!(e.contains("+z") && e.contains("-z"), "{e}");
        assert!(ScenePlacement::check_axes(Some(VolumeAxis::PosZ), Some(VolumeAxis::PosX)).is_ok());
    }
}
