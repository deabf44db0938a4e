//! Frames with a deadline (ANARI_CAVERAY_FRAME_DEADLINE): the display
//! never waits for the ray caster. `anariRenderFrame` starts a full render
//! in the background unless one is running, and a presenter makes the
//! frame ready by the deadline from the newest complete image, warped to
//! the frame's camera (docs/warping.md), or the image itself once the
//! render for this very camera is done in time.

use std::sync::{Arc, Condvar, Mutex, MutexGuard, OnceLock};
use std::time::{Duration, Instant};

use glam::{Vec3, Vec4};

use super::inputs::Inputs;
use super::slot::{FrameSlot, ShownImage, DISCARDED};
use super::status::{About, Note, Notify, Severity, StatusCode};
use super::threads::join_unless_current;
use crate::geometry::RayGen;
use crate::render::warp::{warp_by, Source, WarpMode, WarpSettings, Warped};
use crate::render::{Backend, Frame, FrameDesc, GpuRenderer, RenderError, Renderer};

/// Layers a background render keeps for the `layers` warp (and the warm-up
/// image has, so that it compiles what the real warps run).
pub(super) const WARP_LAYERS: usize = 4;

/// A complete background render, with the inputs it was made for and
/// when its camera was taken.
pub struct Shot {
    pub source: Source,
    pub inputs: Arc<Inputs>,
    pub taken: Instant,
    /// The render's own time, not its wait in the render thread's queue.
    pub took: Duration,
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
    /// Each warp mode's time (by `WarpMode as usize`), from the moment
    /// the presenter meant to wake: the presenter starts that long before
    /// the deadline, and passes over a mode that would miss it. A
    /// passed-over mode's time decays, so it is tried again now and then
    /// (about once a second at 90 Hz for one 4x too slow).
    costs: [Cost; 4],
    /// Whether the host has heard that its warp was passed over.
    told: bool,
}

/// A warp's time in ms, as TCP times a round trip (Jacobson and Karels):
/// a running mean and mean deviation, so that the time reserved covers
/// the spread a loaded machine adds (waking up late, warps of other
/// frames ahead in the pool), not only the mean.
#[derive(Clone, Copy, Default)]
struct Cost {
    /// 0: not measured yet.
    mean: f64,
    deviation: f64,
}

impl Cost {
    fn add(&mut self, ms: f64) {
        if self.mean == 0.0 {
            (self.mean, self.deviation) = (ms, ms / 2.0);
        } else {
            let error = ms - self.mean;
            self.mean += 0.25 * error;
            self.deviation += 0.25 * (error.abs() - self.deviation);
        }
    }

    /// What to reserve before the deadline: the mean, four deviations and
    /// half a millisecond.
    fn reserve(self) -> Duration {
        Duration::from_secs_f64((self.mean + 4.0 * self.deviation + 0.5) / 1e3)
    }

    fn decay(&mut self) {
        self.mean *= 0.97;
        self.deviation *= 0.97;
    }
}

impl Background {
    fn lock(&self) -> MutexGuard<'_, BackState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Claims the background for a render of `inputs`, returning the slot
    /// it renders under; `None` if one is running or the newest image is
    /// already of these inputs.
    pub fn claim(&self, inputs: &Inputs) -> Option<Arc<FrameSlot>> {
        let mut s = self.lock();
        let current = s.newest.as_ref().is_some_and(|n| *n.inputs == *inputs);
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

    /// Stops the render in flight (discard, release), and wakes the
    /// presenters waiting for it, which look at their own stop flags.
    pub fn cancel(&self) {
        let s = self.lock();
        if let Some(slot) = &s.running {
            slot.cancel();
        }
        self.changed.notify_all();
    }

    /// Waits until the image of `inputs` is complete, `until`, or the
    /// presentation in `slot` is stopped; returns the newest image then.
    fn newest_by(&self, inputs: &Inputs, until: Instant, slot: &FrameSlot) -> Option<Arc<Shot>> {
        let mut s = self.lock();
        loop {
            let current = s.newest.as_ref().is_some_and(|n| *n.inputs == *inputs);
            let now = Instant::now();
            if current || now >= until || slot.stopped() {
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

/// What deadline frames warp with, one a device: the CPU, or the
/// renderer of the device's backend (a GPU of its own, so that warps need
/// not wait for the render thread's). Opening a GPU takes longer than a
/// deadline, so it opens on a thread of its own the first time it is
/// wanted, and the CPU warps until it is ready. A GPU warp cannot stop
/// midway, so it runs on a thread of its own too, waited for until the
/// deadline; one that overruns finishes unseen, and the CPU warps until
/// the GPU is free again.
#[derive(Default)]
pub struct Warper {
    state: Mutex<Opened>,
    /// The thread opening a renderer, if one was started.
    opener: Mutex<Option<std::thread::JoinHandle<()>>>,
    /// The thread of the last GPU warp.
    warping: Mutex<Option<std::thread::JoinHandle<()>>>,
}

/// The GPU deadline frames warp with, shared with the warp in flight.
type WarpGpu = Arc<Mutex<Box<GpuRenderer>>>;

#[derive(Default)]
enum Opened {
    #[default]
    Nothing,
    Opening(Backend),
    Ready(Backend, WarpGpu),
    /// No GPU for it: none opened, or `auto` chose the CPU (the CPU warps).
    Failed(Backend),
}

impl Warper {
    /// The newest image shown from the frame's camera by `settings`, on
    /// the backend's GPU if it is open and free, else on the CPU; either
    /// gives up at the deadline (`RenderError::Stopped`).
    fn warp(
        self: &Arc<Self>,
        p: &Present,
        shot: &Arc<Shot>,
        settings: &WarpSettings,
    ) -> Result<Warped, RenderError> {
        let give_up = p.called + p.deadline;
        let backend = p.backend;
        if backend != Backend::Cpu {
            let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
            match &mut *s {
                Opened::Ready(b, g) if *b == backend => {
                    let gpu = Arc::clone(g);
                    drop(s);
                    if let Some(warped) = self.on_gpu(gpu, p, shot, settings, give_up) {
                        return warped;
                    }
                }
                Opened::Opening(b) | Opened::Failed(b) if *b == backend => {}
                _ => {
                    *s = Opened::Opening(backend);
                    let me = Arc::clone(self);
                    let (rays, bounds) = (p.rays, p.bounds);
                    let spawned = std::thread::Builder::new()
                        .name("caveray-warp-open".into())
                        .spawn({
                            let say = Arc::clone(&p.report);
                            move || me.open(backend, (rays, bounds), say)
                        });
                    match spawned {
                        Ok(thread) => {
                            let mut opener = self.opener.lock().unwrap_or_else(|e| e.into_inner());
                            if let Some(old) = opener.replace(thread) {
                                drop(s);
                                join_unless_current(old);
                            }
                        }
                        Err(_) => *s = Opened::Failed(backend),
                    }
                }
            }
        }
        let (rays, size) = (&p.rays, p.desc.size);
        let run = || warp_by(&shot.source, rays, size, settings, Some(give_up));
        match warp_pool() {
            Some(pool) => pool.install(run),
            None => run(),
        }
    }

    /// The warp on `gpu`, on a thread of its own, waited for until
    /// `give_up`; `None` if the last GPU warp is still running (or no
    /// thread could be started): then the CPU warps.
    fn on_gpu(
        &self,
        gpu: WarpGpu,
        p: &Present,
        shot: &Arc<Shot>,
        settings: &WarpSettings,
        give_up: Instant,
    ) -> Option<Result<Warped, RenderError>> {
        let mut warping = self.warping.lock().unwrap_or_else(|e| e.into_inner());
        if warping.as_ref().is_some_and(|t| !t.is_finished()) {
            return None;
        }
        if let Some(done) = warping.take() {
            join_unless_current(done);
        }
        let (tx, rx) = std::sync::mpsc::sync_channel(1);
        let (shot, rays, size, settings) = (Arc::clone(shot), p.rays, p.desc.size, *settings);
        let spawned = std::thread::Builder::new()
            .name("caveray-warp-gpu".into())
            .spawn(move || {
                let mut g = gpu.lock().unwrap_or_else(|e| e.into_inner());
                let warped = g.warp(&shot.source, &rays, size, &settings);
                let _ = tx.send(warped.map(|(w, _)| w));
            });
        *warping = Some(spawned.ok()?);
        drop(warping);
        let wait = give_up.saturating_duration_since(Instant::now());
        Some(rx.recv_timeout(wait).unwrap_or(Err(RenderError::Stopped)))
    }

    /// Waits for the threads opening a renderer and running a GPU warp, if
    /// they run.
    pub fn join(&self) {
        for thread in [&self.opener, &self.warping] {
            let thread = thread.lock().unwrap_or_else(|e| e.into_inner()).take();
            if let Some(thread) = thread {
                join_unless_current(thread);
            }
        }
    }

    /// Opens the backend's GPU and runs each warp once on a small empty
    /// image of `view` (rays and scene bounds), so that the first warp a
    /// frame waits for is not the one that compiles the GPU's shaders.
    fn open(&self, backend: Backend, view: (RayGen, (Vec3, Vec3)), say: Notify) {
        let made = Renderer::choose(backend);
        let message = match made {
            Ok((Renderer::Gpu(mut g), _)) => {
                let warmed = warm_up(&mut g, view);
                let info = g.adapter();
                let m = format!(
                    "deadline frames warp with GPU: {} ({:?}, {}){}",
                    info.name,
                    info.backend,
                    info.driver,
                    warmed
                        .err()
                        .map_or(String::new(), |e| format!("; its first warp failed ({e})"))
                );
                let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
                if !matches!(&*s, Opened::Opening(b) if *b == backend) {
                    return;
                }
                *s = Opened::Ready(backend, Arc::new(Mutex::new(g)));
                m
            }
            other => {
                let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
                if !matches!(&*s, Opened::Opening(b) if *b == backend) {
                    return;
                }
                *s = Opened::Failed(backend);
                match other {
                    // `auto` without a hardware GPU: the CPU warps, on its pool.
                    Ok((_, Some(why))) => format!("deadline frames warp on the CPU: {why}"),
                    Ok((_, None)) => "deadline frames warp on the CPU".into(),
                    Err(e) => format!("deadline frames warp on the CPU: {e}"),
                }
            }
        };
        say(Note {
            severity: Severity::Info,
            code: StatusCode::NoError,
            about: About::Device,
            message,
        });
    }
}

/// Each warp once, on an empty 16 x 16 image of `rays`.
fn warm_up(g: &mut GpuRenderer, (rays, bounds): (RayGen, (Vec3, Vec3))) -> Result<(), RenderError> {
    let size = glam::UVec2::splat(16);
    let source = Source::empty(size, rays, WARP_LAYERS)?;
    for mode in WarpMode::ALL {
        g.warp(&source, &rays, size, &WarpSettings::new(mode, bounds))?;
    }
    Ok(())
}

/// What the presenter of one render needs.
pub struct Present {
    pub background: Arc<Background>,
    pub slot: Arc<FrameSlot>,
    pub inputs: Arc<Inputs>,
    pub rays: RayGen,
    pub desc: FrameDesc,
    pub color: Vec4,
    pub bounds: (Vec3, Vec3),
    pub warp: WarpMode,
    pub called: Instant,
    pub deadline: Duration,
    pub warper: Arc<Warper>,
    pub backend: Backend,
    pub report: Notify,
    /// The frame's handle, which the host's messages name.
    pub frame: u64,
}

/// Fills `p.slot` by the deadline, telling the host first (INFO) when the
/// frame could not show what it asked for.
pub fn present(p: Present) {
    // The warp asked for, unless it took too long last time: then quad,
    // then none, whichever fits (`caveray.warp` says which was shown).
    let (chosen, mut note) = {
        let mut s = p.background.lock();
        // Unmeasured: tried, to learn its time.
        let fits = |m: WarpMode| {
            let cost = s.costs[m as usize];
            cost.mean == 0.0 || cost.reserve() < p.deadline
        };
        let chosen = [p.warp, WarpMode::Quad, WarpMode::None]
            .into_iter()
            .find(|&m| fits(m))
            .unwrap_or(WarpMode::None);
        let note = (chosen != p.warp && !s.told).then(|| {
            s.told = true;
            format!(
                "warp '{}' takes {:.1} ms, too long for the {:.1} ms deadline: '{}' is shown while it would miss it (caveray.warp says which)",
                p.warp.name(),
                s.costs[p.warp as usize].mean,
                p.deadline.as_secs_f64() * 1e3,
                chosen.name()
            )
        });
        if chosen != p.warp {
            s.costs[p.warp as usize].decay();
        }
        (chosen, note)
    };
    let cost = p.background.lock().costs[chosen as usize];
    // A warp not timed yet gets half the deadline to show what it takes.
    let lead = if cost.mean == 0.0 {
        p.deadline / 2
    } else {
        cost.reserve()
    };
    let until = p.called + p.deadline.saturating_sub(lead);
    let newest = p.background.newest_by(&p.inputs, until, &p.slot);
    if p.slot.stopped() {
        return discarded(&p);
    }
    // A warp's time counts from when the presenter meant to wake (or woke
    // for the image it waited for), so that waking late is reserved for.
    let clock = Instant::now().min(until);
    let (frame, shown) = match newest {
        None => {
            note = Some("no image has been rendered yet: the frame shows its background".into());
            (
                Ok(Frame::cleared(&p.desc, p.color)),
                ShownImage {
                    age_ms: -1.0,
                    warp: WarpMode::None,
                    own: false,
                    render_ms: 0.0,
                },
            )
        }
        Some(shot) => {
            let age_ms = p.called.saturating_duration_since(shot.taken).as_secs_f32() * 1e3;
            let own = shot.inputs == p.inputs;
            let render_ms = shot.took.as_secs_f32() * 1e3;
            let mode = if own {
                WarpMode::None
            } else if chosen == WarpMode::None && shot.source.size != p.desc.size {
                // A resized frame cannot show the old image as it is.
                WarpMode::Quad
            } else {
                chosen
            };
            let settings = WarpSettings::new(mode, p.bounds);
            let warped = p
                .warper
                .warp(&p, &shot, &settings)
                .and_then(|w| w.frame(&p.desc, p.color));
            match warped {
                Ok(frame) => (
                    Ok(frame),
                    ShownImage {
                        age_ms,
                        warp: mode,
                        own,
                        render_ms,
                    },
                ),
                Err(e) => {
                    if e == RenderError::Stopped {
                        // Its time so far, where longer than its mean, is one
                        // of its times: the next frames start it earlier or
                        // pass it over.
                        let ms = clock.elapsed().as_secs_f64() * 1e3;
                        let cost = &mut p.background.lock().costs[mode as usize];
                        if ms > cost.mean {
                            cost.add(ms);
                        }
                    }
                    note = Some(match e {
                        RenderError::Stopped => format!(
                            "warp '{}' ran past the deadline; the frame shows the newest image as it is",
                            mode.name()
                        ),
                        e => format!(
                            "warp '{}' failed ({e}); the frame shows the newest image as it is",
                            mode.name()
                        ),
                    });
                    if shot.source.size == p.desc.size {
                        let frame = shot.source.frame(&p.desc, p.color);
                        (
                            frame.map_err(|e| e.to_string()),
                            ShownImage {
                                age_ms,
                                warp: WarpMode::None,
                                own,
                                render_ms,
                            },
                        )
                    } else {
                        // The frame was resized since: the old image does
                        // not fit it unwarped, so its background stands in
                        // until its own render is done.
                        note = note.map(|n| {
                            format!(
                                "{n} (it is {}x{}, the frame {}x{}: the frame shows its background)",
                                shot.source.size.x,
                                shot.source.size.y,
                                p.desc.size.x,
                                p.desc.size.y
                            )
                        });
                        (
                            Ok(Frame::cleared(&p.desc, p.color)),
                            ShownImage {
                                age_ms: -1.0,
                                warp: WarpMode::None,
                                own: false,
                                render_ms: 0.0,
                            },
                        )
                    }
                }
            }
        }
    };
    if shown.age_ms >= 0.0 {
        let ms = clock.elapsed().as_secs_f64() * 1e3;
        p.background.lock().costs[shown.warp as usize].add(ms);
    }
    if p.slot.stopped() {
        // Discarded while it warped: what it made is not shown.
        return discarded(&p);
    }
    if let Some(note) = note {
        (p.report)(Note::frame(
            Severity::Info,
            p.frame,
            format!("frame {:#x}: {note}", p.frame),
        ));
    }
    p.slot.finish_shown(frame, p.called.elapsed(), shown);
}

/// Ends a presentation that was discarded or released: it shows nothing.
fn discarded(p: &Present) {
    let message = format!("rendering frame {:#x} failed: {DISCARDED}", p.frame);
    (p.report)(Note {
        severity: Severity::Info,
        code: StatusCode::UnknownError,
        about: About::Frame(p.frame),
        message,
    });
    p.slot.finish(Err(DISCARDED.into()), p.called.elapsed());
}

#[cfg(test)]
mod tests {
    use super::Cost;

    #[test]
    fn a_steady_warp_reserves_its_time_and_a_jittery_one_its_spread() {
        let mut steady = Cost::default();
        for _ in 0..40 {
            steady.add(2.0);
        }
        // The deviation dies away: the mean and the half millisecond.
        assert!((steady.reserve().as_secs_f64() * 1e3 - 2.5).abs() < 0.01);
        let mut jittery = Cost::default();
        for i in 0..40 {
            jittery.add(if i % 4 == 3 { 8.0 } else { 2.0 });
        }
        // Every fourth warp takes 8 ms: the reserve covers it, where the
        // mean alone (3.5 ms) would not.
        let reserved = jittery.reserve().as_secs_f64() * 1e3;
        assert!(reserved > 8.0, "{reserved}");
        assert!(reserved < 20.0, "{reserved}");
    }
}
