//! The display timeline of the evaluation in Buchacher's thesis (its Figure 18): a
//! display refreshing at `hz` while the ray caster renders cells within
//! each refresh's budget; at every refresh the newest complete image is
//! warped to the view of that instant and compared with the image a
//! renderer without latency would show.

use std::sync::atomic::AtomicBool;

use glam::UVec2;

use super::{Source, WarpMode, WarpSettings};
use crate::geometry::RayGen;
use crate::render::cells::{CellGrid, CellRun};
use crate::render::Render as _;
use crate::render::{dssim, ColorFormat, Frame, FrameDesc, RenderError, RenderSettings, Renderer};
use crate::scene::Scene;

/// A simulated display and renderer.
#[derive(Clone, Debug)]
pub struct Timeline {
    pub hz: f64,
    /// Seconds of display time.
    pub duration: f64,
    pub size: UVec2,
    /// Cells per axis.
    pub cells: UVec2,
    /// The predictions' bias (>= 1).
    pub bias: f64,
    /// Layers kept per pixel for the `layers` warp.
    pub layers: usize,
    /// A full image takes this long (ms), each cell its share: a tenth
    /// spread evenly over the cells, the rest by the cell's share of the
    /// samples. `None`: cells take the time they really take here (the
    /// GPU's pass clock, or the CPU's wall clock).
    pub render_ms: Option<f64>,
    /// Milliseconds kept free before each refresh for the warp itself.
    pub warp_ms: f64,
    pub modes: Vec<WarpMode>,
    /// Bounds, grid spacing and layer steps (the mode is each of `modes`).
    pub warp: WarpSettings,
}

/// One warp's result at one refresh.
pub struct Shown {
    pub mode: WarpMode,
    pub frame: Frame,
    pub dssim: f64,
}

/// What the display showed at one refresh, with the ideal image.
pub struct Refresh {
    pub summary: RefreshSummary,
    pub ideal: Frame,
    pub shown: Vec<Shown>,
}

/// The numbers of one refresh.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RefreshSummary {
    /// Seconds from the path's start.
    pub time: f64,
    /// How old the view of the shown image is (ms).
    pub age_ms: f64,
    /// Cells rendered for this refresh.
    pub cells: u32,
    /// DSSIM of each mode's frame against the ideal one, in `modes` order.
    pub dssim: Vec<f64>,
}

/// The image being rendered and when its view was taken.
struct InFlight {
    source: Source,
    started_ms: f64,
}

impl Timeline {
    /// Why these settings cannot run, if they cannot.
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |m: String| Err(RenderError::Settings(m));
        if !(self.hz.is_finite() && (1.0..=1000.0).contains(&self.hz)) {
            return bad(format!(
                "the display rate must be 1 to 1000 Hz, got {}",
                self.hz
            ));
        }
        if !(self.duration.is_finite() && self.duration > 0.0 && self.duration * self.hz <= 1e5) {
            return bad(format!(
                "the replay must last more than 0 s and at most 100000 refreshes, got {} s at {} Hz",
                self.duration, self.hz
            ));
        }
        if let Some(ms) = self.render_ms {
            if !(ms.is_finite() && ms > 0.0 && ms <= 1e6) {
                return bad(format!(
                    "the simulated render time must be 0 to 1e6 ms, got {ms}"
                ));
            }
        }
        let period = 1e3 / self.hz;
        if !(self.warp_ms.is_finite() && self.warp_ms >= 0.0 && self.warp_ms < period) {
            return bad(format!(
                "the warp's reserve must be at least 0 and less than a refresh ({period:.2} ms), got {}",
                self.warp_ms
            ));
        }
        if self.layers == 0 && self.modes.contains(&WarpMode::Layers) {
            return bad("the layers warp needs at least one layer".into());
        }
        self.warp.validate()
    }

    /// Runs the timeline for the view `view_at` gives at each time
    /// (seconds); `each` sees every refresh's frames as they are made.
    pub fn run(
        &self,
        renderer: &mut Renderer,
        scene: &Scene,
        settings: &RenderSettings,
        view_at: &dyn Fn(f64) -> Result<RayGen, String>,
        each: &mut dyn FnMut(&Refresh),
    ) -> Result<Vec<RefreshSummary>, RenderError> {
        self.validate()?;
        let grid = CellGrid::new(self.size, self.cells).map_err(RenderError::Settings)?;
        let view = |s: f64| view_at(s).map_err(RenderError::Settings);
        let period = 1e3 / self.hz;
        let never = AtomicBool::new(false);
        let mut run = CellRun::new(grid, self.bias);
        // The samples of the last complete image, for simulated times.
        let mut image_samples = 0u64;
        let cell = |renderer: &mut Renderer,
                    run: &mut CellRun,
                    flight: &mut InFlight,
                    image_samples: u64|
         -> Result<f64, RenderError> {
            let i = run.next_cell(f64::INFINITY, true).unwrap_or_default();
            let (offset, size) = grid.rect(i);
            let (part, real) = renderer.capture(
                scene,
                &flight.source.rays.shifted(offset.as_vec2()),
                settings,
                size,
                self.layers,
                &never,
            )?;
            flight.source.paste(offset, &part)?;
            let ms = match self.render_ms {
                None => real,
                Some(total) => {
                    let share = part.samples as f64 / image_samples.max(1) as f64;
                    total * (0.1 / grid.count() as f64 + 0.9 * share)
                }
            };
            run.done(i, ms);
            Ok(ms)
        };
        // A first image, all cells at once: the predictions learn from it.
        let mut flight = InFlight {
            source: Source::empty(self.size, view(0.0)?, self.layers)?,
            started_ms: 0.0,
        };
        let (full, _) =
            renderer.capture(scene, &flight.source.rays, settings, self.size, 0, &never)?;
        image_samples = image_samples.max(full.samples);
        while !run.complete() {
            cell(renderer, &mut run, &mut flight, image_samples)?;
        }
        let mut newest = flight;
        let mut flight = InFlight {
            source: Source::empty(self.size, view(0.0)?, self.layers)?,
            started_ms: 0.0,
        };
        image_samples = newest.source.samples.max(1);
        run.restart();
        let ideal_desc = FrameDesc::new(self.size).with_color(ColorFormat::Rgba32F);
        let refreshes = (self.duration * self.hz).round() as u64;
        let mut debt = 0.0;
        let mut out = Vec::with_capacity(refreshes as usize);
        for k in 1..=refreshes {
            let begin = (k - 1) as f64 * period;
            let budget = period - self.warp_ms;
            let mut left = budget - debt;
            let mut first = true;
            let mut cells = 0;
            while run.next_cell(left, first && left > 0.0).is_some() {
                left -= cell(renderer, &mut run, &mut flight, image_samples)?;
                first = false;
                cells += 1;
                if run.complete() {
                    image_samples = flight.source.samples.max(1);
                    // The renderer began this refresh `debt` late and has
                    // used what is not left since.
                    let now = (begin + budget - left).min(begin + period);
                    let next = InFlight {
                        source: Source::empty(self.size, view(now / 1e3)?, self.layers)?,
                        started_ms: now,
                    };
                    newest = std::mem::replace(&mut flight, next);
                    run.restart();
                }
            }
            // A forced cell that overran comes out of the next budget.
            debt = (-left).max(0.0);
            let shown_ms = k as f64 * period;
            let target = view(shown_ms / 1e3)?;
            let ideal = renderer.render(scene, &target, settings, &ideal_desc)?;
            let mut shown = Vec::with_capacity(self.modes.len());
            for &mode in &self.modes {
                let (warped, _) = renderer.warp(
                    &newest.source,
                    &target,
                    self.size,
                    &WarpSettings { mode, ..self.warp },
                )?;
                let frame = warped.frame(&ideal_desc, settings.background)?;
                let d = dssim(&frame, &ideal)?;
                shown.push(Shown {
                    mode,
                    frame,
                    dssim: d,
                });
            }
            let refresh = Refresh {
                summary: RefreshSummary {
                    time: shown_ms / 1e3,
                    age_ms: shown_ms - newest.started_ms,
                    cells,
                    dssim: shown.iter().map(|s| s.dssim).collect(),
                },
                ideal,
                shown,
            };
            each(&refresh);
            out.push(refresh.summary);
        }
        Ok(out)
    }
}
