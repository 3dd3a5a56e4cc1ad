//! Progress of a run: a one-line bar on a terminal, plain periodic log lines otherwise
//! (or with --quiet), so CI logs stay readable.

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

#[derive(Debug)]
pub struct Progress {
    end_time: f64,
    start: Instant,
    last: Instant,
    every: Duration,
    bar: bool,
    quiet: bool,
    steps: u64,
}

impl Progress {
    pub fn new(end_time: f64, quiet: bool) -> Self {
        let bar = !quiet && std::io::stderr().is_terminal();
        let now = Instant::now();
        Self {
            end_time,
            start: now,
            last: now,
            every: if bar {
                Duration::from_millis(200)
            } else {
                Duration::from_secs(10)
            },
            bar,
            quiet,
            steps: 0,
        }
    }

    /// Called after every step with the simulated time, the step just taken and the
    /// energy-balance error.
    pub fn update(&mut self, step: u64, time: f64, dt: f64, energy_error: f64) {
        self.steps = step;
        let now = Instant::now();
        if now.duration_since(self.last) < self.every {
            return;
        }
        self.last = now;
        let wall = now.duration_since(self.start).as_secs_f64();
        let frac = (time / self.end_time).clamp(0.0, 1.0);
        let rate = step as f64 / wall.max(1e-9);
        let eta = if frac > 0.0 {
            wall * (1.0 - frac) / frac
        } else {
            f64::NAN
        };
        let line = format!(
            "t = {time:.4e} / {:.4e} s ({:>5.1}%), step {step}, {rate:.0} steps/s, ETA {eta:.0} s, dt {dt:.3e} s, energy error {:.2e}",
            self.end_time,
            100.0 * frac,
            energy_error
        );
        let mut err = std::io::stderr().lock();
        if self.bar {
            let width = 30;
            let filled = (frac * width as f64) as usize;
            let _ = write!(
                err,
                "\r[{}{}] {line}\x1b[K",
                "#".repeat(filled),
                " ".repeat(width - filled)
            );
            let _ = err.flush();
        } else if !self.quiet || wall > 0.0 {
            let _ = writeln!(err, "crash: {line}");
        }
    }

    /// A line of its own (a warning): clears the bar first; the bar is redrawn at the
    /// next update.
    pub fn message(&self, line: &str) {
        let mut err = std::io::stderr().lock();
        if self.bar {
            let _ = write!(err, "\r\x1b[K");
        }
        let _ = writeln!(err, "{line}");
        let _ = err.flush();
    }

    pub fn finish(&self) {
        if self.bar {
            eprintln!();
        }
    }
}
