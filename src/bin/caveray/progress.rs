//! A progress bar on stderr; one line per step where stderr is not a terminal.

use std::io::{IsTerminal, Write};
use std::time::Instant;

pub struct Progress {
    total: usize,
    done: usize,
    start: Instant,
    tty: bool,
}

const WIDTH: usize = 30;

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
        // A miscounted total must not bring the tool down.
        let filled = (WIDTH * self.done / self.total.max(1)).min(WIDTH);
        let elapsed = self.start.elapsed().as_secs_f64();
        let line = format!(
            "[{}{}] {}/{} {:.1} s  {note}",
            "#".repeat(filled),
            " ".repeat(WIDTH - filled),
            self.done,
            self.total,
            elapsed
        );
        let mut err = std::io::stderr().lock();
        if self.tty {
            let _ = write!(err, "\r\x1b[2K{line}");
            if self.done == self.total {
                let _ = writeln!(err);
            }
        } else {
            let _ = writeln!(err, "{line}");
        }
        let _ = err.flush();
    }
}
