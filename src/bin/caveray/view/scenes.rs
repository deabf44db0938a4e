//! The volume's scene made anew when its look changes (transfer function,
//! opacity curve, move), on a thread of its own: placing a volume copies
//! and scans its voxels (tens of ms for the CT head), which the window's
//! refreshes must not wait for.

use std::sync::mpsc::{channel, Receiver, Sender};

use anari_library_caveray::cave::{HeadFrame, ScenePlacement};
use anari_library_caveray::geometry::Units;
use anari_library_caveray::scene::Scene;
use glam::Mat4;

use super::controls::Rendering;
use crate::scene::{Loaded, Look};
use crate::Failure;

/// A scene asked for: the look's settings and the volume's move.
struct Ask {
    rendering: Rendering,
    moved: Mat4,
}

/// A scene made, or why not, for the settings asked.
pub struct Made {
    pub rendering: Rendering,
    pub scene: Result<Scene, String>,
}

/// Where the rig places volumes.
#[derive(Clone, Copy)]
pub struct Placing {
    pub placement: ScenePlacement,
    pub frame: HeadFrame,
    pub units: Units,
}

pub struct Scenes {
    ask: Sender<Ask>,
    made: Receiver<Made>,
    /// A scene is being made.
    busy: bool,
    /// The look asked for last (made or refused): not asked for again.
    last: Option<Rendering>,
}

impl Scenes {
    /// `loaded` moves to the thread, which places it as `placing` says.
    pub fn new(mut loaded: Loaded, placing: Placing) -> Result<Self, Failure> {
        let (ask, asked) = channel::<Ask>();
        let (made_tx, made) = channel();
        std::thread::Builder::new()
            .name("caveray-view-scenes".into())
            .spawn(move || {
                while let Ok(mut a) = asked.recv() {
                    // Only the newest look asked for.
                    while let Ok(newer) = asked.try_recv() {
                        a = newer;
                    }
                    let scene = make(&mut loaded, placing, &a);
                    let sent = made_tx.send(Made {
                        rendering: a.rendering,
                        scene: scene.map_err(|(Failure::Usage(e) | Failure::Runtime(e))| e),
                    });
                    if sent.is_err() {
                        return;
                    }
                }
            })
            .map_err(|e| Failure::Runtime(format!("cannot start the scene thread: {e}")))?;
        Ok(Self {
            ask,
            made,
            busy: false,
            last: None,
        })
    }

    /// Asks for the scene of `rendering` and `moved` unless one is being
    /// made or this look was the last asked for.
    pub fn want(&mut self, rendering: &Rendering, moved: Mat4) {
        let same = self.last.as_ref().is_some_and(|l| same_look(l, rendering));
        if self.busy || same {
            return;
        }
        let sent = self.ask.send(Ask {
            rendering: rendering.clone(),
            moved,
        });
        if sent.is_ok() {
            self.busy = true;
            self.last = Some(rendering.clone());
        }
    }

    /// The scene made since the last call, if one was.
    pub fn take(&mut self) -> Option<Made> {
        let made = self.made.try_recv().ok()?;
        self.busy = false;
        Some(made)
    }

    /// The look the scene shown was made for.
    pub fn shown(&mut self, rendering: &Rendering) {
        self.last.get_or_insert_with(|| rendering.clone());
    }
}

/// Whether two settings make the same scene (the renderer's settings
/// aside, which need none).
pub fn same_look(a: &Rendering, b: &Rendering) -> bool {
    a.tf == b.tf
        && a.opacity_gain == b.opacity_gain
        && a.opacity_floor == b.opacity_floor
        && a.volume_offset == b.volume_offset
        && a.volume_yaw == b.volume_yaw
        && a.volume_pitch == b.volume_pitch
}

fn make(loaded: &mut Loaded, p: Placing, a: &Ask) -> Result<Scene, Failure> {
    if a.rendering.tf != loaded.tf_name() {
        loaded.set_tf(&a.rendering.tf)?;
    }
    let look = Look {
        moved: a.moved,
        opacity_gain: a.rendering.opacity_gain,
        opacity_floor: a.rendering.opacity_floor,
    };
    loaded.placed_as(p.placement, &p.frame, p.units, None, &look)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::VolumeArgs;
    use clap::Parser;
    use glam::DVec3;
    use std::time::{Duration, Instant};

    #[derive(Parser)]
    struct Args {
        #[command(flatten)]
        volume: VolumeArgs,
    }

    fn rendering(tf: &str, gain: f32) -> Rendering {
        Rendering {
            opacity_gain: gain,
            ..Rendering::at_rest(tf.into(), &Default::default())
        }
    }

    fn wait(scenes: &mut Scenes) -> Made {
        let start = Instant::now();
        loop {
            if let Some(m) = scenes.take() {
                return m;
            }
            assert!(start.elapsed() < Duration::from_secs(60), "no scene made");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn a_new_look_is_made_off_the_callers_thread_and_a_bad_one_refused_once() {
        let args = Args::parse_from(["t", "--volume", "phantom:16"]);
        let loaded = args.volume.load().ok().unwrap();
        let placing = Placing {
            placement: crate::scene::at(glam::Vec3::ZERO, 2.0),
            frame: HeadFrame::new(DVec3::Y, DVec3::Z).unwrap(),
            units: Units::Metres,
        };
        let first = loaded
            .placed(placing.placement, &placing.frame, placing.units)
            .ok()
            .unwrap();
        let mut scenes = Scenes::new(loaded, placing).ok().unwrap();
        let shown = rendering("phantom", 1.0);
        scenes.shown(&shown);
        // The look shown: nothing to make.
        scenes.want(&shown, Mat4::IDENTITY);
        assert!(!scenes.busy);
        // Another preset, moved: a new scene, its box moved with it.
        let grey = rendering("grey", 0.5);
        let moved = Mat4::from_translation(glam::Vec3::new(1.0, 0.0, 0.0));
        scenes.want(&grey, moved);
        assert!(scenes.busy);
        let made = wait(&mut scenes);
        assert_eq!(made.rendering, grey);
        let scene = made.scene.unwrap();
        assert!(!scene.same(&first));
        let (lo, hi) = (first.bounds(), scene.bounds());
        assert!(
            (hi.0 - lo.0 - glam::Vec3::X).length() < 1e-4,
            "{lo:?} -> {hi:?}"
        );
        // An unknown preset is refused with its reason, and not asked again.
        let bad = rendering("no-such-map", 1.0);
        scenes.want(&bad, Mat4::IDENTITY);
        let refused = wait(&mut scenes);
        assert!(refused.scene.unwrap_err().contains("no-such-map"));
        scenes.want(&bad, Mat4::IDENTITY);
        assert!(!scenes.busy);
    }
}
