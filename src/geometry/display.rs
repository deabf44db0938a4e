//! Multi-view autostereoscopic displays (lenticular or parallax-barrier
//! panels): every subpixel of the panel is seen from one of `views` eye
//! positions, spread along a line in front of it. The model answers which
//! view each subpixel belongs to and where that view's eye is; each view
//! is an off-axis camera on the panel (never toe-in). docs/autostereo.md
//! has the formulas and the shipped display.

use glam::{DVec3, UVec2};

use super::{OffAxisCamera, PrimaryRays, RayGen, Result, Rounded, Screen, Units};

/// The most views a display may have.
pub const MAX_VIEWS: u32 = 64;

/// How the panel's subpixels are assigned to views.
#[derive(Clone, Debug, PartialEq)]
pub enum ViewPattern {
    /// A slanted lens sheet (van Berkel's formula): subpixel column k =
    /// 3x + c of pixel row y lies `u = k + offset − 3·slant·y` subpixels
    /// along the lenses; its view is `floor(frac(u / pitch) · views)`.
    Lens {
        /// Lens width across the panel, in subpixels.
        pitch: f64,
        /// How far the lens moves right per subpixel upward (tan of the
        /// slant angle, in subpixel widths per subpixel height: a row up
        /// moves it 3·slant subpixels).
        slant: f64,
        /// Where the first lens starts, in subpixels.
        offset: f64,
    },
    /// A table of one period of the pattern: `period.x` pixels across by
    /// `period.y` rows up, row by row from the lower left, each pixel's red,
    /// green and blue view.
    Table { period: UVec2, views: Vec<[u32; 3]> },
}

/// The viewing distance, and the length of the line of eyes, a panel may
/// have, in panel widths. Farther, the eyes look from so far that the
/// rays' single-precision origins lose the scene (the panel renders
/// blank); nearer, they graze the panel.
pub const EYES_IN_PANEL_WIDTHS: (f64, f64) = (0.01, 100.0);

/// The lens widths a lens sheet may have, in subpixels. Narrower, `u /
/// pitch` outgrows the precision of its fraction (a lens narrower than a
/// subpixel is a pattern still: tests use 0.47); wider, one lens spans
/// more than any panel and the panel shows one view.
pub const PITCH_RANGE: (f64, f64) = (1.0 / 64.0, 10_000.0);

/// The largest |slant| (tan of the lens's angle from vertical, about 84
/// degrees): steeper, the rows' shift `3 · slant · y` swamps the columns'
/// and a row shows one view.
pub const MAX_SLANT: f64 = 10.0;

/// Which of a display's numbers is out of its range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PanelNumber {
    ViewingDistance,
    ViewSpacing,
    Pitch,
    Slant,
}

impl ViewPattern {
    /// A lens sheet; the offset is taken modulo the pitch (the same
    /// lenses), exactly, so that a large one keeps the subpixels'
    /// positions along the lens.
    pub fn lens(pitch: f64, slant: f64, offset: f64) -> Self {
        let offset = if pitch > 0.0 && offset.is_finite() {
            offset.rem_euclid(pitch)
        } else {
            offset
        };
        ViewPattern::Lens {
            pitch,
            slant,
            offset,
        }
    }
}

/// A multi-view display and where its viewers' eyes are.
#[derive(Clone, Debug, PartialEq)]
pub struct MultiViewDisplay {
    pub name: String,
    pub units: Units,
    /// The panel, as its viewer sees it.
    pub screen: Screen,
    /// Pixels across and up; three subpixels (R, G, B, left to right) each.
    pub resolution: UVec2,
    pub views: u32,
    pub pattern: ViewPattern,
    /// From the panel to the line of eyes, along the panel's normal.
    pub viewing_distance: f64,
    /// Between the eyes of neighbouring views on that line.
    pub view_spacing: f64,
}

impl MultiViewDisplay {
    /// The view subpixel `channel` (0 red, 1 green, 2 blue) of pixel
    /// (x, y) belongs to; y = 0 is the bottom row.
    pub fn view_of(&self, x: u32, y: u32, channel: usize) -> u32 {
        match &self.pattern {
            ViewPattern::Lens {
                pitch,
                slant,
                offset,
            } => {
                let k = 3.0 * f64::from(x) + channel.min(2) as f64;
                let u = k + offset - 3.0 * slant * f64::from(y);
                let along = (u / pitch).rem_euclid(1.0) * f64::from(self.views);
                // A view boundary that falls on a subpixel must not
                // depend on rounding: nudge by far less than a view.
                (along + 1e-9).floor() as u32 % self.views
            }
            ViewPattern::Table { period, views } => {
                let i = (y % period.y) * period.x + x % period.x;
                views[i as usize][channel.min(2)]
            }
        }
    }

    /// Every subpixel's view over `size` pixels, row by row from the lower
    /// left: what a naive renderer interleaves, and what tests compare.
    pub fn view_table(&self, size: UVec2) -> Vec<[u32; 3]> {
        (0..size.y)
            .flat_map(|y| (0..size.x).map(move |x| (x, y)))
            .map(|(x, y)| [0, 1, 2].map(|c| self.view_of(x, y, c)))
            .collect()
    }

    /// The eye of `view`: on the line parallel to the panel's x axis at the
    /// viewing distance in front of its centre, `view_spacing` apart, view
    /// 0 at the right end (a lens sends the light of the subpixels at its
    /// left edge to the right).
    pub fn eye(&self, view: u32) -> DVec3 {
        let s = &self.screen;
        let from_middle = 0.5 * f64::from(self.views - 1) - f64::from(view.min(self.views - 1));
        s.centre()
            + self.viewing_distance * s.normal()
            + from_middle * self.view_spacing * s.x_axis()
    }

    /// The first number that puts the views' eyes out of sight of the
    /// panel, or the panel in one view, and what it must be.
    pub fn out_of_range(&self) -> Option<(PanelNumber, String)> {
        let width = self.screen.width();
        let (lo, hi) = EYES_IN_PANEL_WIDTHS;
        if !(lo * width..=hi * width).contains(&self.viewing_distance) {
            return Some((
                PanelNumber::ViewingDistance,
                format!(
                    "must be from {lo} to {hi} panel widths ({} to {} for this panel)",
                    Rounded(lo * width),
                    Rounded(hi * width)
                ),
            ));
        }
        if f64::from(self.views - 1) * self.view_spacing > hi * width {
            return Some((
                PanelNumber::ViewSpacing,
                format!(
                    "times views - 1 (the line of eyes) must be at most {hi} panel widths ({} for this panel)",
                    Rounded(hi * width)
                ),
            ));
        }
        if let ViewPattern::Lens { pitch, slant, .. } = self.pattern {
            let (lo, hi) = PITCH_RANGE;
            if !(lo..=hi).contains(&pitch) {
                return Some((
                    PanelNumber::Pitch,
                    format!("must be from {lo} to {hi} subpixels"),
                ));
            }
            if !(-MAX_SLANT..=MAX_SLANT).contains(&slant) {
                return Some((
                    PanelNumber::Slant,
                    format!("must be from -{MAX_SLANT} to {MAX_SLANT}"),
                ));
            }
        }
        None
    }

    /// The eye that sees subpixel `channel` of pixel (x, y).
    pub fn subpixel_eye(&self, x: u32, y: u32, channel: usize) -> DVec3 {
        self.eye(self.view_of(x, y, channel))
    }

    /// Every view's rays over the panel's pixels, view 0 first.
    pub fn view_rays(&self) -> Result<Vec<RayGen>> {
        (0..self.views)
            .map(|v| self.view_camera(v).map(|c| c.ray_gen(self.resolution)))
            .collect()
    }

    /// The camera of `view`: the panel seen off-axis from that view's eye.
    pub fn view_camera(&self, view: u32) -> Result<OffAxisCamera> {
        OffAxisCamera::new(self.screen, self.eye(view))
    }
}
