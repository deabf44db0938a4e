//! What the person at `caveray view` controls: the tracked head, the
//! volume, how the walls are rendered and how they are shown. Plain
//! values; keys and drags change them the same way in a window and in
//! tests.

use anari_library_caveray::cave::{HeadPose, Rig};
use anari_library_caveray::render::warp::WarpMode;
use anari_library_caveray::render::{Backend, Shading};
use glam::{DMat4, DQuat, DVec3};

use crate::options::RenderOptions;

/// How the rig is seen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Look {
    /// From an observer outside the rig (orbit with the right button).
    Outside,
    /// From the tracked head: what the person in the rig sees.
    Head,
    /// Every wall's image side by side, pixel for pixel where it fits.
    Flat,
}

impl Look {
    pub const ALL: [Look; 3] = [Look::Outside, Look::Head, Look::Flat];

    pub fn name(self) -> &'static str {
        match self {
            Look::Outside => "outside",
            Look::Head => "head",
            Look::Flat => "flat",
        }
    }

    pub fn next(self) -> Self {
        Self::ALL[(self as usize + 1) % Self::ALL.len()]
    }
}

impl std::str::FromStr for Look {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| format!("expected outside, head or flat, got '{s}'"))
    }
}

/// Which eyes the walls show.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stereo {
    Left,
    Right,
    /// Red (left) and cyan (right).
    Anaglyph,
    /// Each wall's left image beside its right, squeezed.
    SideBySide,
}

impl Stereo {
    pub const ALL: [Stereo; 4] = [
        Stereo::Left,
        Stereo::Right,
        Stereo::Anaglyph,
        Stereo::SideBySide,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Stereo::Left => "left",
            Stereo::Right => "right",
            Stereo::Anaglyph => "anaglyph",
            Stereo::SideBySide => "side-by-side",
        }
    }

    /// Whether the left and the right eye are rendered.
    pub fn eyes(self) -> [bool; 2] {
        match self {
            Stereo::Left => [true, false],
            Stereo::Right => [false, true],
            Stereo::Anaglyph | Stereo::SideBySide => [true, true],
        }
    }

    pub fn next(self) -> Self {
        Self::ALL[(self as usize + 1) % Self::ALL.len()]
    }
}

impl std::str::FromStr for Stereo {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| format!("expected left, right, anaglyph or side-by-side, got '{s}'"))
    }
}

/// Everything that changes what a wall's render is of, and so starts a
/// new background render when it changes (the head aside, which warps).
#[derive(Clone, Debug, PartialEq)]
pub struct Rendering {
    pub tf: String,
    pub opacity_gain: f32,
    pub opacity_floor: f32,
    /// The volume's move from its placement: offset in the rig's units,
    /// then yaw and pitch (degrees) about its centre.
    pub volume_offset: DVec3,
    pub volume_yaw: f64,
    pub volume_pitch: f64,
    pub step_factor: f32,
    pub shading: Shading,
    pub backend: Backend,
}

impl Rendering {
    /// The volume where it was placed, with the preset or map `tf` as it
    /// is, rendered as `options` say.
    pub fn at_rest(tf: String, options: &RenderOptions) -> Self {
        Self {
            tf,
            opacity_gain: 1.0,
            opacity_floor: 0.0,
            volume_offset: DVec3::ZERO,
            volume_yaw: 0.0,
            volume_pitch: 0.0,
            step_factor: options.step_factor,
            shading: options.shading,
            backend: options.backend,
        }
    }
}

/// The window's state: head, volume, renderer settings, how it is shown.
pub struct Controls {
    pub head: DVec3,
    /// Yaw, pitch, roll in degrees in the rig's rest frame.
    pub ypr: DVec3,
    pub rendering: Rendering,
    pub warp: WarpMode,
    pub deadline_ms: f32,
    pub stereo: Stereo,
    pub look: Look,
    /// The head path plays (from `time`).
    pub playing: bool,
    pub time: f64,
    /// The outside observer: yaw and pitch (degrees) about the rig's
    /// centre, and distance in rig sizes.
    pub orbit: [f64; 3],
    /// The view of a multi-view display shown beside its panel.
    pub display_view: u32,
    pub show_panel: bool,
    pub show_figures: bool,
}

/// Keys held this refresh (true while down).
#[derive(Clone, Copy, Debug, Default)]
pub struct Held {
    pub forward: bool,
    pub back: bool,
    pub left: bool,
    pub right: bool,
    pub up: bool,
    pub down: bool,
}

/// Head speed: metres a second.
const WALK_SPEED: f64 = 0.8;
/// Degrees of head turn per pixel of drag.
const TURN_PER_PIXEL: f64 = 0.25;
/// Pitch stops short of straight up or down, where yaw is lost.
const MAX_PITCH: f64 = 85.0;

impl Controls {
    pub fn pose(&self, rig: &Rig) -> HeadPose {
        HeadPose {
            position: self.head,
            orientation: rig.viewer.frame.orientation(self.ypr),
        }
    }

    /// Walks the head for `dt` seconds by the keys held: along its own
    /// forward and right in the rig's floor plane, and up or down; kept in
    /// the tracked space where the rig states one.
    pub fn walk(&mut self, rig: &Rig, held: Held, dt: f64) {
        let f = &rig.viewer.frame;
        let yaw = DQuat::from_axis_angle(f.up, self.ypr.x.to_radians());
        let forward = yaw * f.forward;
        let right = yaw * f.right;
        let axis = |plus: bool, minus: bool| f64::from(u8::from(plus)) - f64::from(u8::from(minus));
        let step = forward * axis(held.forward, held.back)
            + right * axis(held.right, held.left)
            + f.up * axis(held.up, held.down);
        if step == DVec3::ZERO {
            return;
        }
        self.playing = false;
        let speed = WALK_SPEED / rig.units.metres_per_unit();
        self.head += step.normalize() * speed * dt;
        if let Some((lo, hi)) = rig.viewer.tracked_space {
            self.head = self.head.clamp(lo, hi);
        }
    }

    /// Turns the head by a drag of `dx`, `dy` pixels (right and down).
    pub fn turn(&mut self, dx: f64, dy: f64) {
        if dx == 0.0 && dy == 0.0 {
            return;
        }
        self.playing = false;
        self.ypr.x = (self.ypr.x - dx * TURN_PER_PIXEL).rem_euclid(360.0);
        if self.ypr.x > 180.0 {
            self.ypr.x -= 360.0;
        }
        self.ypr.y = (self.ypr.y - dy * TURN_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Turns the volume by a drag (shift and the left button).
    pub fn turn_volume(&mut self, dx: f64, dy: f64) {
        let r = &mut self.rendering;
        r.volume_yaw = (r.volume_yaw + dx * TURN_PER_PIXEL).rem_euclid(360.0);
        r.volume_pitch = (r.volume_pitch + dy * TURN_PER_PIXEL).clamp(-90.0, 90.0);
    }

    /// Orbits the outside observer by a drag (the right button).
    pub fn orbit_by(&mut self, dx: f64, dy: f64) {
        self.orbit[0] -= dx * TURN_PER_PIXEL;
        self.orbit[1] = (self.orbit[1] + dy * TURN_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the outside observer nearer (positive) or farther.
    pub fn zoom(&mut self, steps: f64) {
        self.orbit[2] = (self.orbit[2] * 0.9f64.powf(steps)).clamp(0.3, 8.0);
    }

    /// The head along the rig's path after `dt` more seconds of playing,
    /// from its start again after its end.
    pub fn play(&mut self, rig: &Rig, dt: f64) {
        let (Some(first), Some(last)) = (rig.viewer.path.first(), rig.viewer.path.last()) else {
            self.playing = false;
            return;
        };
        if !self.playing {
            return;
        }
        let span = (last.time - first.time).max(1e-6);
        self.time = first.time + (self.time - first.time + dt).rem_euclid(span);
        let pose = rig.head_at(self.time);
        self.head = pose.position;
        self.ypr = ypr_of(rig, pose.orientation);
    }

    /// The volume's move about `centre` (rig space), as the scene applies
    /// it after the placement.
    pub fn volume_move(&self, rig: &Rig, centre: DVec3) -> DMat4 {
        let f = &rig.viewer.frame;
        let r = &self.rendering;
        let turn = DQuat::from_axis_angle(f.up, r.volume_yaw.to_radians())
            * DQuat::from_axis_angle(f.right, r.volume_pitch.to_radians());
        DMat4::from_translation(centre + r.volume_offset)
            * DMat4::from_quat(turn)
            * DMat4::from_translation(-centre)
    }
}

/// Yaw, pitch and roll (degrees) of `q` in the rig's rest frame: the
/// inverse of `HeadFrame::orientation`.
pub fn ypr_of(rig: &Rig, q: DQuat) -> DVec3 {
    let f = &rig.viewer.frame;
    let forward = q * f.forward;
    let up = q * f.up;
    let yaw = forward.dot(f.right).atan2(forward.dot(f.forward));
    let yaw = -yaw;
    let pitch = forward.dot(f.up).clamp(-1.0, 1.0).asin();
    // Roll: the head's up against the up it would have without roll.
    let without = f.orientation(DVec3::new(yaw.to_degrees(), pitch.to_degrees(), 0.0));
    let plain_up = without * f.up;
    let right = without * f.right;
    let roll = up.dot(right).atan2(up.dot(plain_up));
    DVec3::new(yaw.to_degrees(), pitch.to_degrees(), roll.to_degrees())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rig() -> Rig {
        Rig::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/cave_configs/cologne_5wall.toml"
        )))
        .unwrap()
    }

    fn controls(rig: &Rig) -> Controls {
        Controls {
            head: rig.viewer.head.position,
            ypr: DVec3::ZERO,
            rendering: Rendering::at_rest("ct".into(), &RenderOptions::default()),
            warp: WarpMode::Quad,
            deadline_ms: 16.0,
            stereo: Stereo::Left,
            look: Look::Flat,
            playing: false,
            time: 0.0,
            orbit: [0.0, 20.0, 2.0],
            display_view: 0,
            show_panel: true,
            show_figures: true,
        }
    }

    #[test]
    fn ypr_of_inverts_the_rigs_orientation() {
        let rig = rig();
        for ypr in [
            DVec3::ZERO,
            DVec3::new(40.0, -10.0, 0.0),
            DVec3::new(-120.0, 30.0, 15.0),
        ] {
            let back = ypr_of(&rig, rig.viewer.frame.orientation(ypr));
            assert!((back - ypr).abs().max_element() < 1e-9, "{ypr} -> {back}");
        }
    }

    #[test]
    fn walking_forward_follows_the_heads_yaw_at_walking_speed() {
        let rig = rig();
        let mut c = controls(&rig);
        let start = c.head;
        let held = Held {
            forward: true,
            ..Default::default()
        };
        c.walk(&rig, held, 0.5);
        // 0.8 m/s for half a second, in millimetres, along +y (forward).
        assert!((c.head - start - DVec3::new(0.0, 400.0, 0.0)).length() < 1e-9);
        // Turned 90 degrees left, forward is the rig's -x.
        c.turn(-90.0 / TURN_PER_PIXEL, 0.0);
        assert!((c.ypr.x - 90.0).abs() < 1e-9);
        let here = c.head;
        c.walk(&rig, held, 0.5);
        assert!((c.head - here - DVec3::new(-400.0, 0.0, 0.0)).length() < 1e-6);
        // The tracked space stops the head.
        c.walk(&rig, held, 100.0);
        assert!((c.head.x - -1200.0).abs() < 1e-9);
    }

    #[test]
    fn pitch_stops_short_of_straight_up() {
        let rig = rig();
        let mut c = controls(&rig);
        c.turn(0.0, -10_000.0);
        assert_eq!(c.ypr.y, MAX_PITCH);
    }

    #[test]
    fn playing_follows_the_rigs_path_and_loops() {
        let rig = rig();
        let mut c = controls(&rig);
        c.playing = true;
        c.play(&rig, 4.0);
        let want = rig.head_at(4.0);
        assert!((c.head - want.position).length() < 1e-9);
        assert!((c.ypr - DVec3::new(40.0, -10.0, 0.0)).abs().max_element() < 1e-9);
        // 8 s long: 4 + 5 is 1 s into the next loop.
        c.play(&rig, 5.0);
        assert!((c.time - 1.0).abs() < 1e-9);
        // A walk stops playing.
        c.walk(
            &rig,
            Held {
                left: true,
                ..Default::default()
            },
            0.1,
        );
        assert!(!c.playing);
    }
}
