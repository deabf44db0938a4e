//! Frames with a deadline (ANARI_CAVERAY_FRAME_DEADLINE): the display
//! never waits for the ray caster. `anariRenderFrame` starts a full render
//! in the background unless one is running, and a presenter makes the
//! frame ready by the deadline from the newest complete image, warped to
//! the frame's camera (docs/warping.md), or the image itself once the
//! render for this very camera is done in time.

use std::sync::{Arc, Condvar, Mutex, MutexGuard, OnceLock};
use std::time::{Duration, Instant};

use glam::Vec4;

use super::slot::FrameSlot;
use crate::device::worker::RenderInputs;
use crate::geometry::RayGen;
use crate::render::warp::{warp, Source, WarpMode, WarpSettings};
use crate::render::{Frame, FrameDesc};

/// A complete background render, with the inputs it was made for and
/// when its camera was taken.
pub struct Shot {
    pub source: Source,
    pub inputs: RenderInputs,
    pub taken: Instant,
}

/// A frame's background rendering: the newest complete image and whether
/// a render is running.
#[derive(Default)]
pub struct Background {
    state: Mutex<BackState>,
    changed: Condvar,
}

#[derive(Default)]
struct BackState {
    /// The slot of the render in flight (its stop flag stops it).
    running: Option<Arc<FrameSlot>>,
    newest: Option<Arc<Shot>>,
    /// The last warp's time: the presenter starts that long (and a
    /// margin) before the deadline.
    warp_cost: Duration,
}

/// What a deadline frame showed (properties `caveray.imageAge` and
/// `caveray.warp`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShownImage {
    /// From the camera of the image shown to this render's call (ms); -1
    /// when nothing had been rendered yet and the frame shows its
    /// background.
    pub age_ms: f32,
    /// The warp applied; `None` for the image of this very camera.
    pub warp: WarpMode,
}

impl Background {
    fn lock(&self) -> MutexGuard<'_, BackState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Claims the background for a render of `inputs`, returning the slot
    /// it renders under; `None` if one is running or the newest image is
    /// already of these inputs.
    pub fn claim(&self, inputs: &RenderInputs) -> Option<Arc<FrameSlot>> {
        let mut s = self.lock();
        let current = s.newest.as_ref().is_some_and(|n| n.inputs == *inputs);
        if s.running.is_some() || current {
            return None;
        }
        let slot = Arc::new(FrameSlot::default());
        slot.start();
        s.running = Some(Arc::clone(&slot));
        Some(slot)
    }

    /// The background render ended, with a new image or without.
    pub fn finish(&self, shot: Option<Shot>) {
        let mut s = self.lock();
        s.running = None;
        if let Some(shot) = shot {
            s.newest = Some(Arc::new(shot));
        }
        self.changed.notify_all();
    }

    /// Stops the render in flight (discard, release).
    pub fn cancel(&self) {
        if let Some(slot) = &self.lock().running {
            slot.cancel();
        }
    }

    /// Forgets the newest image (discard: it stands for nothing now).
    pub fn forget(&self) {
        self.lock().newest = None;
    }

    /// Waits until the image of `inputs` is complete or `until`; returns
    /// the newest image then.
    fn newest_by(&self, inputs: &RenderInputs, until: Instant) -> Option<Arc<Shot>> {
        let mut s = self.lock();
        loop {
            let current = s.newest.as_ref().is_some_and(|n| n.inputs == *inputs);
            let now = Instant::now();
            if current || now >= until {
                return s.newest.clone();
            }
            s = self
                .changed
                .wait_timeout(s, until - now)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }
}

/// The threads warps run on: not the global pool, where a CPU background
/// render's tasks would queue them until it finishes.
fn warp_pool() -> Option<&'static rayon::ThreadPool> {
    static POOL: OnceLock<Option<rayon::ThreadPool>> = OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("caveray-warp-{i}"))
            .build()
            .ok()
    })
    .as_ref()
}

/// What the presenter of one render needs.
pub struct Present {
    pub background: Arc<Background>,
    pub slot: Arc<FrameSlot>,
    pub inputs: RenderInputs,
    pub rays: RayGen,
    pub desc: FrameDesc,
    pub colour: Vec4,
    pub bounds: (glam::Vec3, glam::Vec3),
    pub warp: WarpMode,
    pub called: Instant,
    pub deadline: Duration,
}

/// Fills `p.slot` by the deadline; returns a note for the host when the
/// frame could not show what it asked for.
pub fn present(p: Present) -> Option<String> {
    let cost = p.background.lock().warp_cost;
    // Time for the warp itself, and a margin for waking up.
    let reserve = cost.mul_f32(1.25) + Duration::from_micros(500);
    let until = p.called + p.deadline.saturating_sub(reserve);
    let newest = p.background.newest_by(&p.inputs, until);
    let clock = Instant::now();
    let mut note = None;
    let (frame, shown) = match newest {
        None => {
            note = Some("no image has been rendered yet: the frame shows its background".into());
            (
                Ok(Frame::cleared(&p.desc, p.colour)),
                ShownImage {
                    age_ms: -1.0,
                    warp: WarpMode::None,
                },
            )
        }
        Some(shot) => {
            let age_ms = p.called.saturating_duration_since(shot.taken).as_secs_f32() * 1e3;
            let mode = if shot.inputs == p.inputs {
                WarpMode::None
            } else {
                p.warp
            };
            let settings = WarpSettings::new(mode, p.bounds);
            let run = || {
                warp(&shot.source, &p.rays, p.desc.size, &settings)
                    .and_then(|w| w.frame(&p.desc, p.colour))
                    .map_err(|e| e.to_string())
            };
            let warped = match warp_pool() {
                Some(pool) => pool.install(run),
                None => run(),
            };
            match warped {
                Ok(frame) => (Ok(frame), ShownImage { age_ms, warp: mode }),
                Err(e) => {
                    note = Some(format!(
                        "warp '{}' failed ({e}); the frame shows the newest image as it is",
                        mode.name()
                    ));
                    let fallback = if shot.source.size == p.desc.size {
                        shot.source
                            .frame(&p.desc, p.colour)
                            .map_err(|e| e.to_string())
                    } else {
                        Err(format!(
                            "the newest image is {}x{}, the frame {}x{}",
                            shot.source.size.x, shot.source.size.y, p.desc.size.x, p.desc.size.y
                        ))
                    };
                    (
                        fallback,
                        ShownImage {
                            age_ms,
                            warp: WarpMode::None,
                        },
                    )
                }
            }
        }
    };
    p.background.lock().warp_cost = clock.elapsed();
    p.slot.finish_shown(frame, p.called.elapsed(), shown);
    note
}
