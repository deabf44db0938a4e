//! Whether re-projection pays for a view pair, judged from what the last
//! frames of the same view measured. A re-projected pair costs its left
//! pass (the march plus the segment writes) and the compositing; on a wall
//! that sees only a faint edge of the volume that can exceed two plain
//! passes. Costs are kept per view (a wall, a stereo camera, a frame and
//! its partner) and per pose class (one family of epipolar lines or both,
//! which run different pipelines). Where a class has not been measured
//! yet the view's other classes stand in for it: their two passes' times,
//! which no class changes, and their ratio of the paths.
//!
//! A path is measured only when it is rendered, and then [`PairCosts::RUN`]
//! frames in a row, so that no estimate rests on one frame. The paths are
//! compared by the ratio of their last runs rather than by their times:
//! a view's costs drift as the head moves, both paths' alike, and the
//! path not taken keeps the times of a pose long past. Until two passes
//! have been measured, their cost is estimated from the re-projection's
//! left pass (it marches what the left eye marches, and writes segments
//! besides) for the record, but re-projection is not refused on that
//! estimate: it misses where the left pass casts well beyond the image or
//! writes many segments a ray (1.5 to 1.8 times a plain pass on a CAVE
//! side wall at 80²). A view re-projects from its first frame, two passes
//! are measured after [`PairCosts::FIRST_PROBE`] frames of it, and the
//! path not taken is tried again after [`PairCosts::PROBE_AFTER`] frames
//! of a class, to notice a view whose content changed its costs.

use std::collections::{HashMap, HashSet};

/// The two ways to render a pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairPath {
    Reprojected,
    TwoPasses,
}

impl PairPath {
    fn other(self) -> Self {
        match self {
            Self::Reprojected => Self::TwoPasses,
            Self::TwoPasses => Self::Reprojected,
        }
    }
}

/// The path chosen for a pair, and what each path is expected to cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairChoice {
    pub path: PairPath,
    /// Milliseconds each path is expected to take; `None` until measured.
    pub reprojected_ms: Option<f64>,
    pub two_passes_ms: Option<f64>,
    /// The path is rendered to measure it, not because it is expected to
    /// be cheaper.
    pub probe: bool,
}

impl PairChoice {
    /// The expected milliseconds of the chosen path.
    pub fn expected_ms(&self) -> Option<f64> {
        match self.path {
            PairPath::Reprojected => self.reprojected_ms,
            PairPath::TwoPasses => self.two_passes_ms,
        }
    }

    /// Two passes because re-projection measured dearer.
    pub fn refuses_reprojection(&self) -> bool {
        self.path == PairPath::TwoPasses && !self.probe
    }
}

/// The last few measurements of one cost, each with the frame of its
/// view (and class) it was measured in. The fastest of those of one run
/// is the estimate: on a shared machine a pass takes up to twice as long
/// in frames where others hold the cores (lavapipe at 80², two frames in
/// five), and contention only ever slows a pass, so the fastest recent
/// time is the path's own cost.
#[derive(Clone, Copy, Default, Debug)]
struct Recent {
    ms: [f64; Recent::KEPT],
    at: [u64; Recent::KEPT],
    len: usize,
    next: usize,
}

impl Recent {
    const KEPT: usize = 7;

    fn push(&mut self, ms: f64, at: u64) {
        self.ms[self.next] = ms;
        self.at[self.next] = at;
        self.next = (self.next + 1) % Self::KEPT;
        self.len = (self.len + 1).min(Self::KEPT);
    }

    fn latest(&self) -> Option<u64> {
        (self.len > 0).then(|| self.at[(self.next + Self::KEPT - 1) % Self::KEPT])
    }

    /// The times of the latest run: measured within
    /// [`PairCosts::WINDOW`] frames of the latest.
    fn run(&self) -> impl Iterator<Item = f64> + '_ {
        let from = self
            .latest()
            .map_or(0, |l| (l + 1).saturating_sub(PairCosts::WINDOW));
        (0..self.len)
            .filter(move |&i| self.at[i] >= from)
            .map(|i| self.ms[i])
    }

    fn fastest(&self) -> Option<f64> {
        self.run().reduce(f64::min)
    }
}

#[derive(Clone, Copy, Default, Debug)]
struct Costs {
    /// Each path's milliseconds, as [`PairPath`] orders them.
    ms: [Recent; 2],
    /// The re-projection's left pass's milliseconds.
    left_ms: Recent,
    /// Frames recorded, on either path.
    frames: u64,
    /// A re-projected pair's time over two passes', from runs of both
    /// measured within [`PairCosts::WINDOW`] frames of each other.
    ratio: Option<f64>,
}

impl Costs {
    /// Frames since `path` was last measured; all of them if never.
    fn since(&self, path: PairPath) -> u64 {
        self.ms[index(path)]
            .latest()
            .map_or(self.frames, |at| self.frames - 1 - at)
    }

    /// Whether `path` was measured last frame and fewer than RUN times in
    /// its latest run.
    fn running(&self, path: PairPath) -> bool {
        let times = self.ms[index(path)].run().count();
        self.since(path) == 0 && (1..PairCosts::RUN).contains(&times)
    }
}

fn index(path: PairPath) -> usize {
    match path {
        PairPath::Reprojected => 0,
        PairPath::TwoPasses => 1,
    }
}

/// Measured pair costs per view and pose class.
#[derive(Default)]
pub struct PairCosts {
    /// (view, Some(class)) per class; (view, None) over all classes.
    costs: HashMap<(u64, Option<u32>), Costs>,
    told: HashSet<u64>,
}

impl PairCosts {
    /// Frames of a class on one path after which the other is measured
    /// again (about 1.3 s at 90 Hz).
    pub const PROBE_AFTER: u64 = 120;
    /// Re-projected frames of a view after which two passes are measured,
    /// if they never were.
    pub const FIRST_PROBE: u64 = 8;
    /// Frames in a row a path is measured once it is measured at all, so
    /// that neither path's estimate rests on one frame (lavapipe's passes
    /// at 80² vary by half from frame to frame).
    pub const RUN: usize = 3;
    /// Frames within which times belong to one run, and runs of the two
    /// paths are compared: wide enough for paths measured in turn.
    const WINDOW: u64 = 2 * Self::RUN as u64;
    /// Views kept: a host that makes frames without end starts afresh
    /// here rather than growing the table.
    const MAX_VIEWS: usize = 4096;
    /// One eye's pass over the re-projection's left pass, for the
    /// estimate of two passes none were measured for: segment writes add
    /// 5 to 15% to the march on lavapipe (`bench stereo`, 256², no
    /// shading), less where shading adds samples.
    const EYE_SHARE: f64 = 0.9;
    /// Re-projection must be expected this much cheaper to be chosen: a
    /// close call goes to two passes, which are never slower than
    /// themselves, and on small views the passes' noise from frame to
    /// frame (20% and more on lavapipe) exceeds what re-projection saves.
    const MARGIN: f64 = 0.1;

    pub fn new() -> Self {
        Self::default()
    }

    fn get(&self, view: u64, class: Option<u32>) -> Costs {
        self.costs.get(&(view, class)).copied().unwrap_or_default()
    }

    /// The path for view `view`'s pair of pose class `class` (the plan's
    /// family count): re-projection until it has been measured, then the
    /// cheaper one by the ratio of the two paths' last runs (re-projection
    /// only by [`Self::MARGIN`]), and the other after
    /// [`Self::PROBE_AFTER`] frames. A path measured is measured
    /// [`Self::RUN`] frames in a row.
    pub fn choose(&self, view: u64, class: u32) -> PairChoice {
        let own = self.get(view, Some(class));
        let all = self.get(view, None);
        // A view's costs drift as its content moves, and the path not
        // taken keeps the times of its last run: the ratio of the paths'
        // last runs carries their comparison over to the path taken now.
        let by_ratio = |c: &Costs| {
            let fresh = |path: PairPath| c.ms[index(path)].fastest();
            let ratio = c.ratio?;
            if c.since(PairPath::Reprojected) <= c.since(PairPath::TwoPasses) {
                fresh(PairPath::Reprojected).map(|r| (Some(r), Some(r / ratio)))
            } else {
                fresh(PairPath::TwoPasses).map(|t| (Some(t * ratio), Some(t)))
            }
        };
        let fresh = |c: &Costs, path: PairPath| c.ms[index(path)].fastest();
        let estimate = || {
            own.left_ms
                .fastest()
                .or(all.left_ms.fastest())
                .map(|left| 2.0 * Self::EYE_SHARE * left)
        };
        let (t_measured, (reprojected_ms, two_passes_ms)) = match own.ms.map(|m| m.len > 0) {
            // A class its view has seen nothing of yet takes the view's.
            [false, false] => (
                fresh(&all, PairPath::TwoPasses),
                by_ratio(&all).unwrap_or_else(|| {
                    let two = fresh(&all, PairPath::TwoPasses).or_else(estimate);
                    (fresh(&all, PairPath::Reprojected), two)
                }),
            ),
            // Two passes cost the same in every class; re-projection does
            // not, and its ratio to two passes comes from the view's
            // other classes until this one has its own.
            [true, false] => (
                fresh(&all, PairPath::TwoPasses),
                (
                    fresh(&own, PairPath::Reprojected),
                    fresh(&all, PairPath::TwoPasses).or_else(estimate),
                ),
            ),
            [false, true] => {
                let t = fresh(&own, PairPath::TwoPasses);
                let r = match all.ratio {
                    Some(ratio) => t.map(|t| t * ratio),
                    None => fresh(&all, PairPath::Reprojected),
                };
                (t, (r, t))
            }
            [true, true] => (
                fresh(&own, PairPath::TwoPasses),
                by_ratio(&own).unwrap_or((
                    fresh(&own, PairPath::Reprojected),
                    fresh(&own, PairPath::TwoPasses),
                )),
            ),
        };
        let choice = |path, probe| PairChoice {
            path,
            reprojected_ms,
            two_passes_ms,
            probe,
        };
        let cheaper = match (reprojected_ms, two_passes_ms) {
            (None, _) => return choice(PairPath::Reprojected, true),
            // Re-projection was measured without its left pass's time.
            (Some(_), None) => return choice(PairPath::TwoPasses, true),
            // Re-projection is never refused on the estimate alone: it
            // goes on until two passes have been measured, after
            // FIRST_PROBE frames.
            (Some(_), Some(_)) if t_measured.is_none() => {
                if all.since(PairPath::TwoPasses) >= Self::FIRST_PROBE {
                    return choice(PairPath::TwoPasses, true);
                }
                PairPath::Reprojected
            }
            (Some(r), Some(t)) => {
                if r <= (1.0 - Self::MARGIN) * t {
                    PairPath::Reprojected
                } else {
                    PairPath::TwoPasses
                }
            }
        };
        let other = cheaper.other();
        let probe = (own.since(other) >= Self::PROBE_AFTER).then_some(other);
        // A run under way goes on.
        let running = [PairPath::Reprojected, PairPath::TwoPasses]
            .into_iter()
            .find(|&p| own.running(p));
        match running.or(probe) {
            Some(path) => choice(path, path != cheaper),
            None => choice(cheaper, false),
        }
    }

    /// Records that a re-projected pair of the view's class `class` took
    /// `ms`, `left_ms` of it in the left pass; returns the relative error
    /// of the estimate it had (measured over expected, minus 1), if any.
    pub fn record_reprojected(
        &mut self,
        view: u64,
        class: u32,
        ms: f64,
        left_ms: f64,
    ) -> Option<f64> {
        let error = self.record(view, class, PairPath::Reprojected, ms);
        let valid = |v: f64| v.is_finite() && v >= 0.0;
        if valid(ms) && valid(left_ms) {
            for key in [(view, Some(class)), (view, None)] {
                let costs = self.costs.entry(key).or_default();
                costs.left_ms.push(left_ms, costs.frames - 1);
            }
        }
        error
    }

    /// Records that a pair of the view's class `class` took `ms` in two
    /// passes; returns the estimate's relative error, as
    /// [`Self::record_reprojected`] does.
    pub fn record_two_passes(&mut self, view: u64, class: u32, ms: f64) -> Option<f64> {
        self.record(view, class, PairPath::TwoPasses, ms)
    }

    fn record(&mut self, view: u64, class: u32, path: PairPath, ms: f64) -> Option<f64> {
        if !ms.is_finite() || ms < 0.0 {
            return None;
        }
        let expected = self.choose(view, class);
        let expected = match path {
            PairPath::Reprojected => expected.reprojected_ms,
            PairPath::TwoPasses => expected.two_passes_ms,
        };
        if self.costs.len() >= 3 * Self::MAX_VIEWS && !self.costs.contains_key(&(view, None)) {
            self.costs.clear();
            self.told.clear();
        }
        for key in [(view, Some(class)), (view, None)] {
            let costs = self.costs.entry(key).or_default();
            costs.ms[index(path)].push(ms, costs.frames);
            costs.frames += 1;
            if costs.since(path.other()) < Self::WINDOW {
                let fastest = |p: PairPath| costs.ms[index(p)].fastest();
                if let (Some(r), Some(t)) =
                    (fastest(PairPath::Reprojected), fastest(PairPath::TwoPasses))
                {
                    costs.ratio = (t > 0.0).then_some(r / t).or(costs.ratio);
                }
            }
        }
        expected.filter(|&e| e > 0.0).map(|e| ms / e - 1.0)
    }

    /// True the first time view `view` is told its pairs take two passes
    /// on cost, so that a host hears it once.
    pub fn first_refusal(&mut self, view: u64) -> bool {
        self.told.insert(view)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Renders the chosen path at the given costs, as a host would.
    fn frame(
        costs: &mut PairCosts,
        view: u64,
        class: u32,
        reprojected: (f64, f64),
        two: f64,
    ) -> PairChoice {
        let choice = costs.choose(view, class);
        match choice.path {
            PairPath::Reprojected => {
                costs.record_reprojected(view, class, reprojected.0, reprojected.1);
            }
            PairPath::TwoPasses => {
                costs.record_two_passes(view, class, two);
            }
        }
        choice
    }

    #[test]
    fn a_view_that_pays_keeps_reprojecting_from_its_first_frame() {
        let mut costs = PairCosts::new();
        let first = costs.choose(1, 1);
        assert_eq!((first.path, first.probe), (PairPath::Reprojected, true));
        assert_eq!(first.expected_ms(), None);
        // 12 ms a pair, 9 of them the left pass: two passes would take
        // about 2 x 0.9 x 9 = 16.2 ms.
        assert_eq!(costs.record_reprojected(1, 1, 12.0, 9.0), None);
        let second = costs.choose(1, 1);
        assert_eq!((second.path, second.probe), (PairPath::Reprojected, false));
        assert!((second.two_passes_ms.unwrap() - 16.2).abs() < 1e-9);
        // The estimate's error, as measured over expected, minus 1.
        let error = costs.record_reprojected(1, 1, 13.2, 9.0).unwrap();
        assert!((error - 0.1).abs() < 1e-9, "{error}");
        // The fastest of what was measured.
        assert_eq!(costs.choose(1, 1).reprojected_ms, Some(12.0));
        for _ in 0..PairCosts::FIRST_PROBE - 2 {
            assert!(!frame(&mut costs, 1, 1, (12.0, 9.0), 15.0).probe);
        }
        // Then two passes are measured, RUN frames in a row, and lose.
        for _ in 0..PairCosts::RUN {
            let probe = frame(&mut costs, 1, 1, (12.0, 9.0), 15.0);
            assert_eq!((probe.path, probe.probe), (PairPath::TwoPasses, true));
        }
        let after = costs.choose(1, 1);
        assert_eq!(
            (after.path, after.two_passes_ms),
            (PairPath::Reprojected, Some(15.0))
        );
        // And again a probe interval later.
        for _ in 0..PairCosts::PROBE_AFTER {
            assert!(!frame(&mut costs, 1, 1, (12.0, 9.0), 15.0).probe);
        }
        let again = frame(&mut costs, 1, 1, (12.0, 9.0), 15.0);
        assert_eq!((again.path, again.probe), (PairPath::TwoPasses, true));
    }

    #[test]
    fn each_path_is_judged_on_as_many_of_its_times_as_the_other() {
        let mut costs = PairCosts::new();
        // Re-projection measured seven times, once quickly (a quiet
        // frame); two passes once, in an ordinary frame.
        for ms in [9.0, 6.0, 9.0, 9.0, 9.0, 9.0, 9.0] {
            costs.record_reprojected(4, 1, ms, 5.0);
        }
        costs.record_two_passes(4, 1, 9.5);
        // The quick frame is not the latest: re-projection's latest
        // time (9) against two passes' one (9.5) is a close call.
        costs.record_reprojected(4, 1, 9.0, 5.0);
        let choice = costs.choose(4, 1);
        assert_eq!(choice.reprojected_ms, Some(9.0));
        assert_eq!(choice.two_passes_ms, Some(9.5));
        assert_eq!(choice.path, PairPath::TwoPasses);
        // With three times each, the fastest three apiece compare.
        for ms in [9.0, 8.0] {
            costs.record_two_passes(4, 1, ms);
        }
        let choice = costs.choose(4, 1);
        assert_eq!(choice.two_passes_ms, Some(8.0));
        assert_eq!(choice.reprojected_ms, Some(9.0));
    }

    #[test]
    fn a_view_whose_costs_drift_keeps_the_path_its_last_runs_chose() {
        let mut costs = PairCosts::new();
        // A side wall: re-projection a third dearer than two passes.
        for _ in 0..PairCosts::RUN {
            costs.record_reprojected(3, 2, 4.0, 3.0);
            costs.record_two_passes(3, 2, 3.0);
        }
        // The volume fills more of the wall: both paths grow alike, and
        // two passes soon cost more than re-projection's last run did.
        for i in 0..60 {
            let two = 3.0 + 0.05 * f64::from(i);
            let choice = frame(&mut costs, 3, 2, (4.0 / 3.0 * two, two), two);
            assert_eq!(choice.path, PairPath::TwoPasses, "frame {i}");
            let expected = choice.reprojected_ms.unwrap() / choice.two_passes_ms.unwrap();
            assert!((expected - 4.0 / 3.0).abs() < 1e-9, "{expected}");
        }
    }

    #[test]
    fn a_path_taken_after_a_lone_slow_time_is_measured_again_at_once() {
        let mut costs = PairCosts::new();
        costs.record_reprojected(2, 1, 4.0, 2.0);
        // Two passes measured once, on a frame where others held the
        // cores: re-projection looks cheaper than it is.
        costs.record_two_passes(2, 1, 6.0);
        let paths: Vec<_> = (0..PairCosts::RUN + 2)
            .map(|_| frame(&mut costs, 2, 1, (4.0, 2.0), 3.0))
            .collect();
        // The run of two passes goes on, though re-projection looks
        // cheaper, finds their own cost, and they win on it.
        assert_eq!((paths[0].path, paths[0].probe), (PairPath::TwoPasses, true));
        assert!(paths[1..]
            .iter()
            .all(|c| (c.path, c.probe) == (PairPath::TwoPasses, false)));
        assert_eq!(costs.choose(2, 1).two_passes_ms, Some(3.0));
    }

    #[test]
    fn two_passes_are_measured_early_where_the_estimate_flatters_reprojection() {
        let mut costs = PairCosts::new();
        // A left pass that costs twice a plain one: the estimate of two
        // passes (2 x 0.9 x 16 = 28.8 ms) hides that they take 17.
        let mut paths = Vec::new();
        for _ in 0..12 {
            paths.push(frame(&mut costs, 9, 1, (18.0, 16.0), 17.0).path);
        }
        let first_two = paths.iter().position(|&p| p == PairPath::TwoPasses);
        assert_eq!(first_two, Some(PairCosts::FIRST_PROBE as usize));
        assert!(paths[PairCosts::FIRST_PROBE as usize..]
            .iter()
            .all(|&p| p == PairPath::TwoPasses));
        assert!(costs.choose(9, 1).refuses_reprojection());
    }

    #[test]
    fn a_view_where_compositing_outweighs_the_saving_takes_two_passes() {
        let mut costs = PairCosts::new();
        // A faint edge of the volume: a 2 ms left pass, 2 ms compositing.
        // The estimate of two passes (3.6 ms) is not enough to refuse.
        costs.record_reprojected(5, 2, 4.0, 2.0);
        let choice = costs.choose(5, 2);
        assert_eq!(choice.path, PairPath::Reprojected);
        assert!((choice.two_passes_ms.unwrap() - 3.6).abs() < 1e-9);
        // Two passes measured: they win.
        let error = costs.record_two_passes(5, 2, 3.96).unwrap();
        assert!((error - 0.1).abs() < 1e-9, "{error}");
        let choice = costs.choose(5, 2);
        assert_eq!(choice.two_passes_ms, Some(3.96));
        assert!(choice.refuses_reprojection());
    }

    #[test]
    fn a_close_call_goes_to_two_passes() {
        let mut costs = PairCosts::new();
        costs.record_reprojected(6, 1, 9.7, 8.0);
        costs.record_two_passes(6, 1, 10.0);
        assert!(costs.choose(6, 1).refuses_reprojection());
        let mut costs = PairCosts::new();
        costs.record_reprojected(6, 1, 8.9, 8.0);
        for _ in 0..PairCosts::RUN {
            costs.record_two_passes(6, 1, 10.0);
        }
        assert_eq!(costs.choose(6, 1).path, PairPath::Reprojected);
    }

    #[test]
    fn views_are_apart_and_a_new_class_borrows_its_views_costs() {
        let mut costs = PairCosts::new();
        costs.record_reprojected(1, 1, 5.0, 4.0);
        costs.record_two_passes(1, 1, 9.0);
        assert_eq!(costs.choose(2, 1).expected_ms(), None);
        let borrowed = costs.choose(1, 2);
        assert_eq!(borrowed.path, PairPath::Reprojected);
        assert!(!borrowed.probe);
        assert_eq!(borrowed.reprojected_ms, Some(5.0));
        // Its own measurements then count for it: 20 ms, measured a run
        // of frames, against the 9 ms two passes took in the other class.
        for _ in 0..PairCosts::RUN {
            frame(&mut costs, 1, 2, (20.0, 4.0), 9.0);
        }
        let own = costs.choose(1, 2);
        assert_eq!(
            (own.reprojected_ms, own.two_passes_ms),
            (Some(20.0), Some(9.0))
        );
        assert!(own.refuses_reprojection());
        let first = costs.choose(1, 1);
        assert_eq!(
            (first.reprojected_ms, first.two_passes_ms),
            (Some(5.0), Some(9.0))
        );
    }

    #[test]
    fn a_host_making_views_without_end_does_not_grow_the_table() {
        let mut costs = PairCosts::new();
        for view in 0..3 * PairCosts::MAX_VIEWS as u64 {
            costs.record_reprojected(view, 1 + (view % 2) as u32, 1.0, 1.0);
        }
        assert!(costs.costs.len() <= 3 * PairCosts::MAX_VIEWS);
        let last = 3 * PairCosts::MAX_VIEWS as u64 - 1;
        assert!(costs.choose(last, 2).reprojected_ms.is_some());
    }

    #[test]
    fn the_path_not_taken_is_measured_again_and_can_win_back() {
        let mut costs = PairCosts::new();
        costs.record_reprojected(7, 1, 30.0, 20.0);
        costs.record_two_passes(7, 1, 20.0);
        let mut frames = 0;
        // The content changed: re-projection now costs 10 ms.
        while !frame(&mut costs, 7, 1, (10.0, 8.0), 20.0).probe {
            frames += 1;
            assert!(frames <= PairCosts::PROBE_AFTER, "never measured again");
        }
        assert_eq!(frames, PairCosts::PROBE_AFTER - 1);
        // The probe's 10 ms replace the stale 30 ms: re-projection wins.
        let now = costs.choose(7, 1);
        assert_eq!(now.reprojected_ms, Some(10.0));
        assert_eq!((now.path, now.probe), (PairPath::Reprojected, false));
    }

    #[test]
    fn one_slow_frame_does_not_flip_the_choice() {
        let mut costs = PairCosts::new();
        costs.record_reprojected(8, 1, 6.0, 5.0);
        costs.record_two_passes(8, 1, 9.0);
        for _ in 0..5 {
            frame(&mut costs, 8, 1, (6.0, 5.0), 9.0);
        }
        // A pass twice as slow as the others, as a busy machine gives.
        costs.record_reprojected(8, 1, 12.0, 10.0);
        let choice = costs.choose(8, 1);
        assert_eq!(
            (choice.path, choice.reprojected_ms),
            (PairPath::Reprojected, Some(6.0))
        );
    }

    #[test]
    fn bad_times_are_ignored_and_refusals_are_told_once() {
        let mut costs = PairCosts::new();
        assert_eq!(costs.record_reprojected(3, 1, f64::NAN, 1.0), None);
        assert_eq!(costs.record_reprojected(3, 1, -1.0, 1.0), None);
        assert_eq!(costs.record_two_passes(3, 1, f64::INFINITY), None);
        assert_eq!(costs.choose(3, 1).expected_ms(), None);
        assert!(costs.first_refusal(3));
        assert!(!costs.first_refusal(3));
        assert!(costs.first_refusal(4));
    }
}
