//! Runs what the device hands it: the render thread and its renderers,
//! and every execution policy: unchanged frames keeping their image,
//! per-eye stereo pairing (`pairing`), the one re-projection decision
//! (`render::stereo::decide`, applied in `passes`), multi-view panels,
//! deadline presentation and its warps (`deadline`), and discards. The
//! engine knows nothing of ANARI objects: the device gives it each
//! frame's inputs as plain values (`Inputs`) and the frame's render state
//! (`FrameRenders`), and hears back through a `Notify`, a callback it
//! hands each `Note` to from any of its threads.
//!
//! # Threads
//!
//! - **The host's threads** call the device. A call never waits for a
//!   render while it holds the device: where a frame is still rendering,
//!   the device answers with the frame's `FrameSlot`, and the C layer
//!   waits on it without the device and calls again.
//! - **The render thread** (`caveray-render`, one a device, owned by the
//!   `Worker` inside `Engine`): started by the first render, it takes jobs
//!   from a channel in order (whole renders, stereo pairs, panels,
//!   isosurfaces, deadline frames' background renders) and waits on
//!   nothing else. It calls frame completion callbacks after it finishes
//!   the frame's slot. Dropping the engine stops its jobs and joins it,
//!   unless the drop runs on the render thread itself (a callback that
//!   releases the device): then the thread ends by itself when the
//!   callback returns.
//! - **Presenter threads** (`caveray-present`, one a deadline render,
//!   owned by `Engine` and joined when it goes): each waits on its frame's
//!   `Background` until the image it wants is done, the deadline comes or
//!   the frame is discarded, then warps and calls the completion callback.
//! - **The warper's opener** (`caveray-warp-open`, at most one at a time,
//!   owned by the `Warper`): opens the second GPU deadline frames warp
//!   with, runs each warp once to compile it, and waits for nothing.
//! - **The GPU warp** (`caveray-warp-gpu`, at most one at a time, owned by
//!   the `Warper`): a presenter waits for it until the deadline only; one
//!   that overruns finishes unseen while the CPU warps. The CPU warps on a
//!   rayon pool of its own (`caveray-warp-N`), never the render thread's.
//!
//! No thread joins or waits for itself: a join is skipped on the thread
//! being joined, and `FrameSlot::wait` returns at once to the thread that
//! is to finish the render (the device then says that the frame is still
//! rendering). Every kind of render looks at its slot's stop flag, which a
//! discard or a release sets: the ray casters between rows (GPU passes
//! between bands of rows), the passes between views and passes, the
//! background render while it captures, a presenter while it waits and
//! after it warps. Dropping the engine stops the presenters before it
//! joins them, so it never waits for a deadline.

mod accumulation;
mod data_parallel;
mod deadline;
mod inputs;
mod job;
mod pairing;
mod passes;
mod slot;
mod status;
mod threads;
mod worker;

use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::Vec3;

pub use data_parallel::cannot_render;
pub use deadline::{Background, Present, Warper};
pub use inputs::{EyeView, Inputs, PanelViews, Share, Unrenderable, Views};
pub use job::{BackgroundRender, FrameRenders, Partner, RenderJob};
pub use pairing::{OwnEye, Unpaired};
pub use slot::{FrameSlot, Kept, ShownImage, SlotState, DISCARDED};
pub use status::{panic_message, About, Note, Notify, Severity, StatusCode};

use deadline::Shot;
use threads::join_unless_current;
use worker::Worker;

use crate::render::warp::{Source, WarpMode};

/// A frame's deadline: how long after the render call it must be ready,
/// and how it brings an older image to its camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deadline {
    pub after: Duration,
    pub warp: WarpMode,
}

/// A deadline frame's presenter thread and what stops it.
struct Presenter {
    thread: JoinHandle<()>,
    slot: Arc<FrameSlot>,
    background: Arc<Background>,
}

/// One device's engine: its render thread, its deadline presenters and
/// what they warp with.
pub struct Engine {
    worker: Worker,
    /// What deadline frames warp with.
    warper: Arc<Warper>,
    /// Deadline frames' presenter threads, stopped and joined when the
    /// engine goes.
    presenters: Vec<Presenter>,
    report: Notify,
}

impl Engine {
    /// `report` receives what the engine's threads have to say.
    pub fn new(report: Notify) -> Self {
        Self {
            worker: Worker::new(Arc::clone(&report)),
            warper: Default::default(),
            presenters: Vec::new(),
            report,
        }
    }

    /// Hands a job to the render thread; its slot must be started.
    pub fn submit(&mut self, job: RenderJob) {
        self.worker.submit(job);
    }

    /// Starts a deadline frame's render of `inputs`: the full render in the
    /// background unless one is running or the newest image is of these
    /// inputs, and says what the presenter needs. `warn` hears what the
    /// host should know first.
    pub fn begin_deadline(
        &mut self,
        frame: u64,
        renders: &FrameRenders,
        inputs: Arc<Inputs>,
        deadline: Deadline,
        warn: &mut dyn FnMut(String),
    ) -> Result<Present, String> {
        let called = Instant::now();
        let warp = deadline.warp;
        let view = match &inputs.views {
            Views::Panel(_) => return Err("a frame with caveray.deadline shows one view: set the multi-view camera's 'view', or render the panel image without a deadline".into()),
            _ if !inputs.surfaces.is_empty() => return Err("a frame with caveray.deadline warps volume images; this world holds isosurfaces (render it without a deadline)".into()),
            _ if inputs.desc.hits => return Err("a frame with caveray.deadline warps color and depth; unset its id, normal and albedo channels (or its deadline)".into()),
            Views::StereoPair(_) => return Err("a frame with caveray.deadline shows one view: set the camera's stereoMode to none (each eye its own frame)".into()),
            Views::Mono(view) => *view,
        };
        if inputs.settings.background_image.is_some() {
            warn("it shows the renderer's background color, not its background image".into());
        }
        let background = Arc::clone(&renders.background);
        let bounds = inputs
            .scene
            .as_ref()
            .map_or((Vec3::ZERO, Vec3::ZERO), |s| s.bounds());
        let present = Present {
            background: Arc::clone(&background),
            slot: Arc::clone(&renders.slot),
            inputs: Arc::clone(&inputs),
            rays: view.rays,
            desc: inputs.desc,
            color: inputs.settings.background,
            bounds,
            warp,
            called,
            deadline: deadline.after,
            warper: Arc::clone(&self.warper),
            backend: inputs.backend,
            report: Arc::clone(&self.report),
            frame,
        };
        if inputs.scene.is_some() {
            if let Some(slot) = background.claim(&inputs) {
                self.worker.submit(RenderJob {
                    frame,
                    inputs,
                    slot,
                    on_done: None,
                    unchanged: false,
                    sample: None,
                    partner: None,
                    background: Some(BackgroundRender {
                        target: background,
                        warp,
                        taken: called,
                    }),
                });
            }
        } else {
            // An empty world: its image is the background, at once.
            background.finish(Some(Shot {
                source: Source::empty(inputs.desc.size, view.rays, 0).map_err(|e| e.to_string())?,
                inputs,
                taken: called,
                took: Duration::ZERO,
            }));
        }
        Ok(present)
    }

    /// Runs a deadline frame's presenter on its own thread: the frame is
    /// ready by its deadline whatever the background render does. Its slot
    /// must be started.
    pub fn spawn_presenter(&mut self, present: Present, on_done: Option<Box<dyn FnOnce() + Send>>) {
        self.presenters.retain(|p| !p.thread.is_finished());
        let slot = Arc::clone(&present.slot);
        let background = Arc::clone(&present.background);
        let spawned = std::thread::Builder::new()
            .name("caveray-present".into())
            .spawn(move || {
                present.slot.hand_to(std::thread::current().id());
                deadline::present(present);
                if let Some(done) = on_done {
                    done();
                }
            });
        match spawned {
            Ok(thread) => self.presenters.push(Presenter {
                thread,
                slot,
                background,
            }),
            Err(e) => slot.finish(
                Err(format!("cannot start the frame's presenter: {e}")),
                Default::default(),
            ),
        }
    }

    /// Stops the presenters and waits for them and the warper's opener:
    /// no thread of ours may outlive the device, as the host may unload
    /// the library right after releasing it. A stopped presenter ends at
    /// once, its frame discarded, whatever its deadline; the warper's GPU
    /// opens in about a second.
    pub fn stop_presenters(&mut self) {
        for p in &self.presenters {
            p.slot.cancel();
            p.background.cancel();
        }
        for p in self.presenters.drain(..) {
            join_unless_current(p.thread);
        }
        self.warper.join();
    }
}

impl Drop for Engine {
    /// The presenters and the warper's opener first; the render thread
    /// then goes with the worker, which stops its jobs.
    fn drop(&mut self) {
        self.stop_presenters();
    }
}
