//! ANARI_KHR_CAMERA_STEREO on the perspective camera: one eye shifted half
//! the interpupillary distance along the camera's right vector, or both
//! eyes side by side or one above the other in one frame. (On a CAVE wall
//! this is the wrong stereo: each eye needs its own off-axis frustum, so
//! hosts there give each eye its own camera.)

use glam::{DVec3, UVec2};

use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, ParamInfo, F32};
use crate::device::types::DataType as T;

/// `stereoMode` and `interpupillaryDistance`, as every stereo camera
/// declares them.
pub const fn params() -> [ParamInfo; 2] {
    [
        p(
            "stereoMode",
            &[T::STRING],
            false,
            DefaultValue::Text("none"),
            "none, left, right, sideBySide (left eye in the left half) or topBottom (left eye on top)",
        )
        .names(StereoMode::NAMES),
        p(
            "interpupillaryDistance",
            F32,
            false,
            DefaultValue::Floats(&[0.0635]),
            "distance between the eyes of stereoMode, in world units (0.0635 in a scene of metres, 63.5 in one of millimetres)",
        )
        .at_least(0.0),
    ]
}

/// The values of `stereoMode`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StereoMode {
    #[default]
    None,
    Left,
    Right,
    /// The left eye in the left half of the frame, the right eye in the
    /// right half.
    SideBySide,
    /// The left eye in the top half (the upper rows: ANARI images start at
    /// the lower left), the right eye in the bottom half.
    TopBottom,
}

impl StereoMode {
    pub const NAMES: &'static [&'static str] =
        &["none", "left", "right", "sideBySide", "topBottom"];

    pub fn parse(name: &str) -> Result<Self, String> {
        Ok(match name {
            "none" => StereoMode::None,
            "left" => StereoMode::Left,
            "right" => StereoMode::Right,
            "sideBySide" => StereoMode::SideBySide,
            "topBottom" => StereoMode::TopBottom,
            other => {
                return Err(format!(
                    "stereoMode \"{other}\" is not one of {}",
                    Self::NAMES.join(", ")
                ))
            }
        })
    }

    /// Why a frame of `size` cannot hold both eyes of this mode: halving
    /// a side of one pixel leaves one eye no pixels at all.
    pub fn fits(self, size: UVec2) -> Result<(), String> {
        let (side, across) = match self {
            StereoMode::SideBySide => ("wide", size.x),
            StereoMode::TopBottom => ("high", size.y),
            _ => return Ok(()),
        };
        if across >= 2 {
            return Ok(());
        }
        Err(format!(
            "stereoMode {} splits the frame between the eyes, so it must be at least 2 pixels {side}; this frame is {}x{}",
            self.name(),
            size.x,
            size.y
        ))
    }

    pub fn name(self) -> &'static str {
        match self {
            StereoMode::None => "none",
            StereoMode::Left => "left",
            StereoMode::Right => "right",
            StereoMode::SideBySide => "sideBySide",
            StereoMode::TopBottom => "topBottom",
        }
    }

    /// The eyes (-1 left, +1 right) and where each goes in a frame of
    /// `size`: (eye, offset, size); each eye has pixels where `fits`.
    pub fn layout(self, size: UVec2) -> Vec<(f64, UVec2, UVec2)> {
        match self {
            StereoMode::None => vec![(0.0, UVec2::ZERO, size)],
            StereoMode::Left => vec![(-1.0, UVec2::ZERO, size)],
            StereoMode::Right => vec![(1.0, UVec2::ZERO, size)],
            StereoMode::SideBySide => {
                let left = size.x / 2;
                vec![
                    (-1.0, UVec2::ZERO, UVec2::new(left, size.y)),
                    (1.0, UVec2::new(left, 0), UVec2::new(size.x - left, size.y)),
                ]
            }
            StereoMode::TopBottom => {
                let bottom = size.y / 2;
                vec![
                    (
                        -1.0,
                        UVec2::new(0, bottom),
                        UVec2::new(size.x, size.y - bottom),
                    ),
                    (1.0, UVec2::ZERO, UVec2::new(size.x, bottom)),
                ]
            }
        }
    }
}

/// The camera's stereo parameters after commit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stereo {
    pub mode: StereoMode,
    /// In world units.
    pub ipd: f64,
}

impl Stereo {
    /// The committed `params()`. The distance is the host's, in its
    /// world's units, so no upper bound fits every scene: what cannot
    /// give an image is refused at render, where the world is known
    /// (`CameraModel::check_eyes`).
    pub fn from_params(r: &Read<'_>) -> Result<Self, String> {
        Self::read(
            r.string("stereoMode").unwrap_or_default(),
            r.f32_in_range("interpupillaryDistance")?,
        )
    }

    pub fn read(mode: &str, ipd: f32) -> Result<Self, String> {
        if !(ipd.is_finite() && ipd >= 0.0) {
            return Err(format!(
                "interpupillaryDistance must be a finite number >= 0, got {ipd:?}"
            ));
        }
        Ok(Self {
            mode: StereoMode::parse(mode)?,
            ipd: ipd.into(),
        })
    }

    /// Where eye `side` (-1 left, +1 right) stands for a camera at
    /// `position` looking along `direction` with `up`.
    pub fn eye(&self, side: f64, position: DVec3, direction: DVec3, up: DVec3) -> DVec3 {
        self.along(side, position, direction.cross(up))
    }

    /// Eye `side` of eyes centred on `centre`, apart along `axis`.
    pub fn along(&self, side: f64, centre: DVec3, axis: DVec3) -> DVec3 {
        if side == 0.0 {
            return centre;
        }
        centre + axis.normalize_or_zero() * (0.5 * self.ipd * side)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_cover_the_frame_once() {
        for size in [UVec2::new(7, 5), UVec2::new(64, 32), UVec2::new(1, 2)] {
            for mode in [
                StereoMode::SideBySide,
                StereoMode::TopBottom,
                StereoMode::None,
            ] {
                let area: u32 = mode.layout(size).iter().map(|(_, _, s)| s.x * s.y).sum();
                assert_eq!(area, size.x * size.y, "{mode:?} {size}");
            }
        }
        let tb = StereoMode::TopBottom.layout(UVec2::new(4, 6));
        assert_eq!(
            tb[0],
            (-1.0, UVec2::new(0, 3), UVec2::new(4, 3)),
            "left on top"
        );
    }

    #[test]
    fn eyes_sit_half_the_distance_along_right() {
        let s = Stereo::read("left", 0.064).unwrap();
        let eye = s.eye(-1.0, DVec3::ZERO, DVec3::NEG_Z, DVec3::Y);
        assert!((eye - DVec3::new(-0.032, 0.0, 0.0)).length() < 1e-7);
        assert!(Stereo::read("cross-eyed", 0.06)
            .unwrap_err()
            .contains("sideBySide"));
        assert!(Stereo::read("left", -1.0).is_err());
    }

    #[test]
    fn a_split_frame_needs_two_pixels_across_the_split() {
        for mode in [StereoMode::SideBySide, StereoMode::TopBottom] {
            for size in [UVec2::new(2, 2), UVec2::new(64, 32)] {
                assert!(mode.fits(size).is_ok(), "{mode:?} {size}");
                assert!(mode
                    .layout(size)
                    .iter()
                    .all(|(_, _, s)| s.min_element() > 0));
            }
        }
        assert!(StereoMode::SideBySide.fits(UVec2::new(1, 9)).is_err());
        assert!(StereoMode::SideBySide.fits(UVec2::new(9, 1)).is_ok());
        assert!(StereoMode::TopBottom.fits(UVec2::new(1, 9)).is_ok());
        assert!(StereoMode::TopBottom.fits(UVec2::new(9, 1)).is_err());
        assert!(StereoMode::Left.fits(UVec2::ONE).is_ok());
    }
}
