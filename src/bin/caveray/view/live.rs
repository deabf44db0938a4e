//! The walls of `caveray view`, live through the device's own engine:
//! every wall and eye is a frame with a deadline. Each refresh hands the
//! engine the views of the current head; the engine renders in the
//! background and a presenter makes each frame ready by its deadline from
//! the newest image warped to that head (docs/warping.md). Nothing here
//! waits for a render: a pane whose frame is still being presented keeps
//! showing its last one.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anari_library_caveray::engine::EyeView;
use anari_library_caveray::engine::{
    Deadline, Engine, FrameRenders, Inputs, Note, Severity, ShownImage, Views,
};
use anari_library_caveray::geometry::RayGen;
use anari_library_caveray::render::warp::WarpMode;
use anari_library_caveray::render::{Backend, FrameDesc, RenderSettings, StreamWait};
use anari_library_caveray::scene::Scene;
use glam::UVec2;

/// How many of the engine's newest messages the window keeps to show.
const KEEP_NOTES: usize = 6;

/// What one refresh asks of every pane.
pub struct Ask<'a> {
    pub scene: &'a Scene,
    pub settings: &'a RenderSettings,
    pub backend: Backend,
    pub deadline: Deadline,
}

/// A presented frame of a pane: its image and what the presenter said.
pub struct Presented {
    pub size: UVec2,
    /// sRGB-encoded RGBA, top row first.
    pub pixels: Vec<u8>,
    pub shown: ShownImage,
    /// From the render call to the frame being ready.
    pub ready: Duration,
}

/// One wall's eye: its deadline frame and what it showed.
#[derive(Default)]
struct Pane {
    renders: FrameRenders,
    /// The inputs of the frame being presented.
    asked: Option<Arc<Inputs>>,
    /// The inputs of the newest frame shown, and what it showed.
    shown_for: Option<Arc<Inputs>>,
    last: Option<ShownImage>,
    /// The inputs of the current head, asked for this refresh.
    wanted: Option<Arc<Inputs>>,
    stats: PaneStats,
}

/// Running figures of a pane for the overlay and the benchmark.
#[derive(Clone, Copy, Debug, Default)]
pub struct PaneStats {
    pub frames: u64,
    /// Frames ready after their deadline (more than a millisecond late).
    pub late: u64,
    pub max_ready_ms: f64,
    pub sum_ready_ms: f64,
    pub max_age_ms: f64,
    pub sum_age_ms: f64,
    /// Frames that showed a warped image, and their own image.
    pub warped: u64,
    pub own: u64,
    /// When the newest frame came, and the rate frames come at (a running
    /// mean).
    pub last_at: Option<Instant>,
    pub rate_hz: f64,
    pub last: Option<ShownImage>,
}

pub struct Live {
    engine: Engine,
    panes: Vec<Pane>,
    notes: Arc<Mutex<Vec<String>>>,
}

impl Live {
    pub fn new(panes: usize) -> Self {
        let notes = Arc::new(Mutex::new(Vec::<String>::new()));
        let sink = Arc::clone(&notes);
        let engine = Engine::new(Arc::new(move |n: Note| {
            if (n.severity as i32) <= Severity::Warning as i32 {
                eprintln!("caveray view: {}", n.message);
            }
            let mut notes = sink.lock().unwrap_or_else(|e| e.into_inner());
            if notes.last() != Some(&n.message) {
                notes.push(n.message);
            }
            let extra = notes.len().saturating_sub(KEEP_NOTES);
            notes.drain(..extra);
        }));
        Self {
            engine,
            panes: (0..panes).map(|_| Pane::default()).collect(),
            notes,
        }
    }

    /// The engine's newest messages.
    pub fn notes(&self) -> Vec<String> {
        self.notes.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    pub fn stats(&self, pane: usize) -> PaneStats {
        self.panes[pane].stats
    }

    /// Whether every pane in `wanted` shows its own image of the views
    /// asked for last.
    pub fn converged(&self, wanted: &[usize]) -> bool {
        wanted.iter().all(|&i| {
            let p = &self.panes[i];
            let current = match (&p.shown_for, &p.wanted) {
                (Some(shown), Some(wanted)) => **shown == **wanted,
                _ => false,
            };
            current && p.last.is_some_and(|s| s.own)
        })
    }

    /// One refresh: takes every frame that is ready, and starts the next
    /// frame of each pane in `views` (pane, rays, size) whose frame is not
    /// being presented. Returns the new frames by pane.
    pub fn refresh(
        &mut self,
        ask: &Ask,
        views: &[(usize, RayGen, UVec2)],
    ) -> Vec<(usize, Presented)> {
        let mut out = Vec::new();
        for &(index, rays, size) in views {
            let pane = &mut self.panes[index];
            let inputs = Arc::new(Inputs {
                scene: Some(ask.scene.clone()),
                surfaces: Vec::new(),
                views: Views::Mono(EyeView {
                    rays,
                    offset: UVec2::ZERO,
                    size,
                    matrix: None,
                }),
                settings: ask.settings.clone(),
                desc: FrameDesc::new(size),
                backend: ask.backend,
                gpu_budget: None,
                stream_wait: StreamWait::Complete,
                accumulate: false,
                share: None,
            });
            pane.wanted = Some(Arc::clone(&inputs));
            if pane.renders.slot.is_busy() {
                continue;
            }
            if let Some(asked) = pane.asked.take() {
                let state = pane.renders.slot.lock();
                if let (Some(Ok(frame)), Some(shown)) = (&state.result, state.shown) {
                    let presented = Presented {
                        size: frame.size,
                        pixels: frame.to_srgb8_top_down(),
                        shown,
                        ready: state.duration,
                    };
                    drop(state);
                    pane.last = Some(shown);
                    pane.shown_for = Some(asked);
                    pane.stats.record(&presented, ask.deadline.after);
                    out.push((index, presented));
                }
            }
            let mut warnings = Vec::new();
            let present = self.engine.begin_deadline(
                index as u64,
                &pane.renders,
                Arc::clone(&inputs),
                ask.deadline,
                &mut |w| warnings.push(w),
            );
            for w in warnings {
                eprintln!("caveray view: {w}");
            }
            match present {
                Ok(present) => {
                    pane.renders.presenting();
                    pane.renders.slot.start();
                    self.engine.spawn_presenter(present, None);
                    pane.asked = Some(inputs);
                }
                Err(e) => eprintln!("caveray view: pane {index}: {e}"),
            }
        }
        out
    }

    /// Forgets what `pane` showed (after a change of scene): it counts as
    /// converged again once a frame of the new inputs shows its own image.
    pub fn forget(&mut self, pane: usize) {
        let p = &mut self.panes[pane];
        p.shown_for = None;
        p.last = None;
    }
}

impl PaneStats {
    fn record(&mut self, p: &Presented, deadline: Duration) {
        let ready_ms = p.ready.as_secs_f64() * 1e3;
        self.frames += 1;
        self.sum_ready_ms += ready_ms;
        self.max_ready_ms = self.max_ready_ms.max(ready_ms);
        if ready_ms > deadline.as_secs_f64() * 1e3 + 1.0 {
            self.late += 1;
        }
        if p.shown.age_ms >= 0.0 {
            let age = f64::from(p.shown.age_ms);
            self.sum_age_ms += age;
            self.max_age_ms = self.max_age_ms.max(age);
        }
        if p.shown.warp != WarpMode::None {
            self.warped += 1;
        }
        if p.shown.own {
            self.own += 1;
        }
        let now = Instant::now();
        if let Some(then) = self.last_at {
            let hz = 1.0 / now.duration_since(then).as_secs_f64().max(1e-6);
            self.rate_hz = if self.rate_hz == 0.0 {
                hz
            } else {
                0.9 * self.rate_hz + 0.1 * hz
            };
        }
        self.last_at = Some(now);
        self.last = Some(p.shown);
    }
}
