//! The slot a frame's render fills and the host waits on.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::ThreadId;
use std::time::Duration;

use super::accumulation::Accumulated;
use super::inputs::Inputs;
use crate::render::warp::WarpMode;
use crate::render::{Frame, Residency};

/// What a render that was stopped leaves in its frame.
pub const DISCARDED: &str = "the render was discarded (anariDiscardFrame)";

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
    /// Whether the image was rendered for this render's very inputs (its
    /// camera, scene and settings), not an older one shown warped or as
    /// it is.
    pub own: bool,
    /// How long the render of the image shown took (ms); 0 for the
    /// background.
    pub render_ms: f32,
}

/// Shared between the device and the thread rendering into the frame.
#[derive(Default)]
pub struct FrameSlot {
    state: Mutex<SlotState>,
    done: Condvar,
    /// Set by a discard or a release: the render in flight stops where it
    /// can (between the CPU reference's rows, the GPU's bands of rows, or
    /// the passes and views of a job) and keeps no image.
    pub stop: AtomicBool,
    /// This frame's eye from a stereo pass another frame rendered, for
    /// the inputs it was made from.
    kept: Mutex<Option<Kept>>,
}

/// An image made for a frame by its stereo partner's render.
pub struct Kept {
    /// What this frame's render must ask for to be given the image.
    pub inputs: Arc<Inputs>,
    pub frame: Frame,
    /// This eye's share of the pass.
    pub duration: Duration,
    /// The frame whose render made it.
    pub by: u64,
}

#[derive(Default)]
pub struct SlotState {
    pub busy: bool,
    pub result: Option<Result<Frame, String>>,
    pub duration: Duration,
    /// Renders the image stands for: 1 after a render, one more for each
    /// render of unchanged inputs (what an accumulating host counts).
    pub samples: u32,
    /// What a deadline frame showed; `None` for a whole render.
    pub shown: Option<ShownImage>,
    /// What the last render's volumes hold in memory, once one ran.
    pub resident: Option<Residency>,
    /// The share of the bricks of paged volumes the last render selected
    /// that it rendered with, once one ran.
    pub progress: Option<f32>,
    /// The samples of a refined image (accumulation), once it has more
    /// than its first.
    accumulated: Option<Accumulated>,
    /// The thread that will finish the render in flight, once it has it.
    finisher: Option<ThreadId>,
}

impl SlotState {
    /// `FrameSlot::finishes_here` for a caller that holds the lock (the
    /// mutex is not re-entrant: locking it again would wait for ever).
    pub fn finishes_here(&self) -> bool {
        self.busy && self.finisher == Some(std::thread::current().id())
    }
}

impl FrameSlot {
    pub fn lock(&self) -> MutexGuard<'_, SlotState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub fn start(&self) {
        let mut s = self.lock();
        s.busy = true;
        s.finisher = None;
        self.stop.store(false, Ordering::Relaxed);
    }

    /// The render in flight is `thread`'s to finish.
    pub fn hand_to(&self, thread: ThreadId) {
        let mut s = self.lock();
        if s.busy {
            s.finisher = Some(thread);
        }
    }

    /// Whether a render is in flight that only the calling thread can
    /// finish (a completion callback on the render thread asking about a
    /// frame queued behind its own): waiting for it would never end.
    pub fn finishes_here(&self) -> bool {
        self.lock().finishes_here()
    }

    /// Whether the last render succeeded; then a render of the same
    /// inputs may keep its image.
    pub fn holds_image(&self) -> bool {
        matches!(self.lock().result, Some(Ok(_)))
    }

    /// Ends a render that kept the last image: only the duration changes.
    pub fn finish_unchanged(&self, duration: Duration) {
        let mut s = self.lock();
        s.duration = duration;
        s.samples = s.samples.saturating_add(1);
        s.busy = false;
        s.finisher = None;
        self.done.notify_all();
    }

    /// Ends a render of one more sample of the frame's unchanged inputs
    /// (accumulation): the image becomes the mean of its samples. A
    /// sample that failed leaves the image as it was, and says why.
    pub fn finish_sample(
        &self,
        sample: Result<Frame, String>,
        duration: Duration,
    ) -> Result<(), String> {
        let mut guard = self.lock();
        let s = &mut *guard;
        let added = match (sample, &s.result) {
            (Ok(sample), Some(Ok(shown))) => {
                let samples = s.samples;
                let acc = s
                    .accumulated
                    .get_or_insert_with(|| Accumulated::new(shown, samples));
                acc.add(&sample).and_then(|()| acc.image(shown))
            }
            (Ok(_), _) => Err("internal: no image to refine".into()),
            (Err(e), _) => Err(e),
        };
        let outcome = match added {
            Ok(image) => {
                s.samples = s.accumulated.as_ref().map_or(1, Accumulated::samples);
                s.result = Some(Ok(image));
                Ok(())
            }
            Err(e) => Err(e),
        };
        s.duration = duration;
        s.busy = false;
        s.finisher = None;
        self.done.notify_all();
        outcome
    }

    /// How many samples the image stands for, if it is a good one.
    pub fn image_samples(&self) -> Option<u32> {
        let s = self.lock();
        matches!(s.result, Some(Ok(_))).then_some(s.samples)
    }

    pub fn finish(&self, result: Result<Frame, String>, duration: Duration) {
        self.finish_as(result, duration, None);
    }

    /// Ends a deadline frame's presentation, saying what it showed.
    pub fn finish_shown(
        &self,
        result: Result<Frame, String>,
        duration: Duration,
        shown: ShownImage,
    ) {
        self.finish_as(result, duration, Some(shown));
    }

    fn finish_as(
        &self,
        result: Result<Frame, String>,
        duration: Duration,
        shown: Option<ShownImage>,
    ) {
        let mut s = self.lock();
        s.samples = u32::from(result.is_ok());
        s.accumulated = None;
        s.result = Some(result);
        s.duration = duration;
        s.shown = shown;
        s.busy = false;
        s.finisher = None;
        self.done.notify_all();
    }

    /// Keeps `kept` for this frame's next render.
    pub fn keep(&self, kept: Kept) {
        *self.kept.lock().unwrap_or_else(|e| e.into_inner()) = Some(kept);
    }

    /// The kept image if it was made for `inputs`; a kept image for other
    /// inputs is dropped, never shown.
    pub fn take_kept(&self, inputs: &Inputs) -> Option<Kept> {
        let kept = self.kept.lock().unwrap_or_else(|e| e.into_inner()).take()?;
        (*kept.inputs == *inputs).then_some(kept)
    }

    /// Whether a kept image waits for `inputs`.
    pub fn keeps(&self, inputs: &Inputs) -> bool {
        self.kept
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_ref()
            .is_some_and(|k| *k.inputs == *inputs)
    }

    /// Blocks until no render is in flight; returns the state locked. The
    /// thread that is to finish the render is not made to wait for itself:
    /// it gets the state at once, still busy.
    pub fn wait(&self) -> MutexGuard<'_, SlotState> {
        let me = std::thread::current().id();
        let mut s = self.lock();
        while s.busy && s.finisher != Some(me) {
            s = self.done.wait(s).unwrap_or_else(|e| e.into_inner());
        }
        s
    }

    pub fn is_busy(&self) -> bool {
        self.lock().busy
    }

    /// Stops the render in flight, if any (discard, release).
    pub fn cancel(&self) {
        let s = self.lock();
        if s.busy {
            self.stop.store(true, Ordering::Relaxed);
        }
    }

    /// Whether the render in flight was asked to stop.
    pub fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_finishing_thread_never_waits_for_itself() {
        let slot = Arc::new(FrameSlot::default());
        slot.start();
        slot.hand_to(std::thread::current().id());
        assert!(slot.finishes_here());
        assert!(slot.wait().busy, "returns at once, still busy");
        // Another thread waits until this one finishes the render.
        let other = {
            let slot = Arc::clone(&slot);
            std::thread::spawn(move || {
                assert!(!slot.finishes_here());
                slot.wait().busy
            })
        };
        std::thread::sleep(Duration::from_millis(20));
        slot.finish(Err("done".into()), Duration::ZERO);
        assert!(!other.join().unwrap());
        assert!(!slot.finishes_here());
    }

    #[test]
    fn only_a_busy_slot_is_stopped() {
        let slot = FrameSlot::default();
        slot.cancel();
        assert!(!slot.stopped());
        slot.start();
        slot.cancel();
        assert!(slot.stopped());
        slot.start();
        assert!(!slot.stopped(), "a new render starts unstopped");
    }
}
