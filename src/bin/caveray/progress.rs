//! A progress bar on stderr; one line per step where stderr is not a
//! terminal. While a view renders, the bar also moves within it: a thread
//! redraws it from the renderer's counter every quarter second on a
//! terminal, and writes a line every few seconds elsewhere, so that logs
//! of long renders stay short but still show they are moving.

use std::io::{IsTerminal, Write};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use anari_library_caveray::render;

pub struct Progress {
    total: usize,
    done: usize,
    start: Instant,
    tty: bool,
}

const WIDTH: usize = 30;

/// How often a terminal's bar is redrawn within a view.
const REDRAW: Duration = Duration::from_millis(250);

/// How often a line is written within a view where stderr is not a
/// terminal, unless `$CAVERAY_PROGRESS_EVERY` gives other seconds.
const LOG_EVERY: Duration = Duration::from_secs(5);

impl Progress {
    pub fn new(total: usize) -> Self {
        Self {
            total,
            done: 0,
            start: Instant::now(),
            tty: std::io::stderr().is_terminal(),
        }
    }

    /// Marks one step done, with a note about it.
    pub fn step(&mut self, note: &str) {
        self.done += 1;
        let line = format!(
            "{}  {note}",
            self.line(self.done as f64, self.start.elapsed())
        );
        self.write(&line, self.done == self.total);
    }

    /// Runs `work`, which renders the next `views` steps (a wall's two
    /// eyes from one pass are two), counting its units into the counter
    /// it is given; meanwhile the bar shows how much of it (`label`) is
    /// done. The caller marks the steps done after.
    pub fn within<T>(
        &self,
        views: usize,
        label: &str,
        work: impl FnOnce(&render::Progress) -> T,
    ) -> T {
        let counter = render::Progress::new();
        let (done, finished) = channel::<()>();
        std::thread::scope(|scope| {
            let counter = &counter;
            scope.spawn(move || self.redraw(counter, views, label, finished));
            let out = work(counter);
            // The redrawing thread stops at once, not at its next tick.
            drop(done);
            out
        })
    }

    /// Redraws the bar from `counter` until `finished` disconnects.
    fn redraw(
        &self,
        counter: &render::Progress,
        views: usize,
        label: &str,
        finished: Receiver<()>,
    ) {
        let every = if self.tty { REDRAW } else { log_every() };
        loop {
            match finished.recv_timeout(every) {
                Err(RecvTimeoutError::Timeout) => {}
                _ => return,
            }
            let view = counter.get().fraction().unwrap_or(0.0);
            let steps = self.done as f64 + views as f64 * view;
            let line = format!(
                "{}  {label} {}%",
                self.line(steps, self.start.elapsed()),
                (view * 100.0).floor()
            );
            self.write(&line, false);
        }
    }

    /// The bar after `steps` steps (whole or not), `elapsed` into the run,
    /// with the run's estimated time left.
    fn line(&self, steps: f64, elapsed: Duration) -> String {
        // A miscounted total must not bring the tool down.
        let total = self.total.max(1) as f64;
        let fraction = (steps / total).clamp(0.0, 1.0);
        let filled = ((WIDTH as f64 * fraction) as usize).min(WIDTH);
        let mut line = format!(
            "[{}{}] {}/{} {}",
            "#".repeat(filled),
            " ".repeat(WIDTH - filled),
            self.done,
            self.total,
            seconds(elapsed.as_secs_f64())
        );
        if fraction > 0.0 && fraction < 1.0 {
            let left = elapsed.as_secs_f64() * (1.0 - fraction) / fraction;
            line += &format!(", ETA {}", seconds(left));
        }
        line
    }

    fn write(&self, line: &str, last: bool) {
        let mut err = std::io::stderr().lock();
        if self.tty {
            let _ = write!(err, "\r\x1b[2K{line}");
            if last {
                let _ = writeln!(err);
            }
        } else {
            let _ = writeln!(err, "{line}");
        }
        let _ = err.flush();
    }
}

/// `$CAVERAY_PROGRESS_EVERY` (seconds, at least 0.01), else LOG_EVERY.
fn log_every() -> Duration {
    std::env::var("CAVERAY_PROGRESS_EVERY")
        .ok()
        .and_then(|s| s.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.01 && *s <= 86_400.0)
        .map_or(LOG_EVERY, Duration::from_secs_f64)
}

/// `s` seconds as "12.3 s", "4 min 05 s" or "2 h 07 min".
fn seconds(s: f64) -> String {
    if !s.is_finite() {
        return "?".into();
    }
    if s < 60.0 {
        return format!("{s:.1} s");
    }
    let whole = s.round() as u64;
    if whole < 3600 {
        format!("{} min {:02} s", whole / 60, whole % 60)
    } else {
        format!("{} h {:02} min", whole / 3600, whole % 3600 / 60)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_read_in_the_largest_sensible_unit() {
        assert_eq!(seconds(12.34), "12.3 s");
        assert_eq!(seconds(245.0), "4 min 05 s");
        assert_eq!(seconds(7620.0), "2 h 07 min");
        assert_eq!(seconds(f64::INFINITY), "?");
    }

    #[test]
    fn the_estimate_comes_from_the_fraction_done() {
        let p = Progress {
            total: 4,
            done: 1,
            start: Instant::now(),
            tty: false,
        };
        // A step and a half of four in 3 s: 5 s left.
        let line = p.line(1.5, Duration::from_secs(3));
        assert!(line.contains("1/4 3.0 s, ETA 5.0 s"), "{line}");
        assert!(!p.line(4.0, Duration::from_secs(3)).contains("ETA"));
    }
}
