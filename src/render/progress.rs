//! How far a render has come, and when to give it up: a counter the
//! renderers add to as they finish their units of work (CPU tiles or rows,
//! GPU bands), read from any thread while they run, and the stop flag it
//! travels with.
//!
//! Units by path: `render` on the CPU counts 16 x 16 tiles, the CPU's
//! warp capture and isosurface casts count rows; every GPU pass counts
//! bands of rows (about 2^18 pixels each, 2^14 on a software adapter),
//! finished, not merely submitted. A re-projected stereo pair counts the
//! left eye's bands and one more for the compositing; a multi-view panel
//! counts each of its passes' rows or bands. Shading (shadows, ambient
//! occlusion) runs inside the same units, so it makes them slower, not
//! more numerous.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// Units done out of the units a render announced, as one atomic word
/// (done in the low 32 bits, the total in the high 32), so a reader never
/// sees a done from one render with a total from another. Shared by
/// reference: `Sync`, and cheap to read (one load).
#[derive(Debug, Default)]
pub struct Progress(AtomicU64);

/// One reading of a [`Progress`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Done {
    pub done: u32,
    /// What the render announced; 0 before it has.
    pub total: u32,
}

impl Done {
    /// `done / total` in [0, 1]; `None` before a total was announced.
    pub fn fraction(self) -> Option<f64> {
        (self.total > 0).then(|| (f64::from(self.done) / f64::from(self.total)).min(1.0))
    }
}

const DONE_BITS: u32 = 32;
const DONE_MASK: u64 = (1 << DONE_BITS) - 1;

impl Progress {
    pub const fn new() -> Self {
        Self(AtomicU64::new(0))
    }

    pub fn get(&self) -> Done {
        let word = self.0.load(Ordering::Relaxed);
        Done {
            done: (word & DONE_MASK) as u32,
            total: (word >> DONE_BITS) as u32,
        }
    }

    /// Back to nothing announced, nothing done: before the next render
    /// counts into it.
    pub fn reset(&self) {
        self.0.store(0, Ordering::Relaxed);
    }

    /// Announces `units` more to do. Totals stop at `u32::MAX`; no path
    /// comes near (a frame is at most 2^28 pixels, 2^20 tiles).
    fn expect(&self, units: u64) {
        let _ = self
            .0
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |word| {
                let total = (word >> DONE_BITS).saturating_add(units).min(DONE_MASK);
                Some(total << DONE_BITS | word & DONE_MASK)
            });
    }

    /// Marks `units` done: one atomic add, a unit's cost next to its rays.
    fn advance(&self, units: u64) {
        self.0.fetch_add(units, Ordering::Relaxed);
    }
}

/// What a render looks at while it runs: `stop` (once set, no further
/// unit starts and the render fails with `RenderError::Stopped`) and the
/// [`Progress`] it counts into, if any. A `&AtomicBool` converts into
/// one, so every render that takes a `Watch` also takes a bare stop flag,
/// and so does a `&Progress` (a render that is never stopped).
#[derive(Clone, Copy, Debug)]
pub struct Watch<'a> {
    stop: &'a AtomicBool,
    progress: Option<&'a Progress>,
    /// Whether whoever runs this render as one part of a larger one has
    /// announced its units already.
    announced: bool,
}

impl<'a> Watch<'a> {
    pub fn new(stop: &'a AtomicBool) -> Self {
        Self {
            stop,
            progress: None,
            announced: false,
        }
    }

    /// The same watch, counting into `progress`, which the render adds
    /// its units to (reset it between renders to count each from zero).
    pub fn counting(self, progress: &'a Progress) -> Self {
        Self {
            progress: Some(progress),
            ..self
        }
    }

    pub fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// Announces the render's `units` before its first one starts, unless
    /// a larger render it is part of announced them.
    pub(crate) fn expect(&self, units: u64) {
        match self.progress {
            Some(p) if !self.announced => p.expect(units),
            _ => {}
        }
    }

    pub(crate) fn advance(&self, units: u64) {
        if let Some(p) = self.progress {
            p.advance(units);
        }
    }

    /// This watch for one part of a render that announced every part's
    /// units itself (several surfaces, a pass per view), so the fraction
    /// done never falls back as the next part starts.
    pub(crate) fn part(self) -> Self {
        Self {
            announced: true,
            ..self
        }
    }
}

impl<'a> From<&'a AtomicBool> for Watch<'a> {
    fn from(stop: &'a AtomicBool) -> Self {
        Self::new(stop)
    }
}

/// The stop flag of a watch made from a progress alone: nothing sets it,
/// as no watch hands its flag out.
static NEVER: AtomicBool = AtomicBool::new(false);

impl<'a> From<&'a Progress> for Watch<'a> {
    fn from(progress: &'a Progress) -> Self {
        Self::new(&NEVER).counting(progress)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reading_pairs_the_done_with_its_total() {
        let (stop, p) = (AtomicBool::new(false), Progress::new());
        let watch = Watch::new(&stop).counting(&p);
        assert_eq!(p.get().fraction(), None);
        watch.expect(4);
        watch.advance(1);
        assert_eq!(p.get(), Done { done: 1, total: 4 });
        assert_eq!(p.get().fraction(), Some(0.25));
        // A part of a render that announced its units adds no more.
        watch.part().expect(4);
        watch.part().advance(3);
        assert_eq!(p.get(), Done { done: 4, total: 4 });
        p.reset();
        assert_eq!(p.get(), Done::default());
        // Totals saturate instead of spilling into nothing.
        watch.expect(u64::MAX);
        assert_eq!(p.get().total, u32::MAX);
        // Without a counter, counting costs nothing and changes nothing.
        let bare = Watch::from(&stop);
        bare.expect(3);
        bare.advance(3);
        assert!(!bare.stopped());
        let counted = Watch::from(&p);
        counted.advance(1);
        assert_eq!(p.get().done, 1);
        assert!(!counted.stopped());
    }
}
