//! Progress of a run: an indicatif bar on a terminal, cut to the terminal's width at
//! every redraw; plain periodic log lines otherwise (stderr not a terminal, or
//! --quiet), with no escape codes, so logs kept in files stay plain text. Lines of
//! their own (warnings) go through the bar so the two never tear.

use indicatif::{HumanDuration, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// Bar positions: the fraction of the end time in thousandths.
const BAR_LEN: u64 = 1000;
/// Plain lines: one every this many seconds.
const PLAIN_EVERY: Duration = Duration::from_secs(10);
/// The bar: at most this many redraws per second (indicatif limits the draws too).
const BAR_EVERY: Duration = Duration::from_millis(200);

/// Where the run stands after a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Status {
    pub step: u64,
    /// Simulated time reached and the end time [s].
    pub time: f64,
    pub end_time: f64,
    /// The step just taken [s].
    pub dt: f64,
    pub energy_error: f64,
    /// Wall time still needed at the rate since this process started (None: unknown).
    pub eta: Option<Duration>,
    /// Steps per wall second since this process started.
    pub rate: f64,
}

impl Status {
    pub fn fraction(&self) -> f64 {
        if self.end_time > 0.0 {
            (self.time / self.end_time).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    fn eta_text(&self) -> String {
        self.eta
            .map_or_else(|| "?".into(), |d| format!("{:#}", HumanDuration(d)))
    }

    /// The plain log line (no escape codes).
    pub fn plain_line(&self) -> String {
        format!(
            "crash: t = {:.4e} / {:.4e} s ({:.1}%), step {}, {:.0} steps/s, ETA {}, dt {:.3e} s, energy error {:.2e}",
            self.time,
            self.end_time,
            100.0 * self.fraction(),
            self.step,
            self.rate,
            self.eta_text(),
            self.dt,
            self.energy_error
        )
    }

    /// The bar's text, most important first (a narrow terminal cuts the end).
    pub fn bar_message(&self) -> String {
        format!(
            "{:.1}% t {:.4e}/{:.4e} s  step {}  ETA {}  dt {:.2e} s  energy error {:.1e}",
            100.0 * self.fraction(),
            self.time,
            self.end_time,
            self.step,
            self.eta_text(),
            self.dt,
            self.energy_error
        )
    }
}

/// Cells of the bar drawn for a terminal `width` columns wide (0: text only).
pub fn bar_cells(width: usize) -> usize {
    match width {
        0..=49 => 0,
        50..=99 => 12,
        _ => 24,
    }
}

fn style(cells: usize) -> ProgressStyle {
    // `wide_msg` takes the columns left and cuts the text to them: the line never
    // wraps, whatever the width
    let template = if cells == 0 {
        "{wide_msg}".to_string()
    } else {
        format!("[{{bar:{cells}}}] {{wide_msg}}")
    };
    ProgressStyle::with_template(&template)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ")
}

#[derive(Debug)]
struct Bar {
    pb: ProgressBar,
    /// The terminal's width when it cannot be asked (tests draw into a fixed one).
    fixed_width: Option<usize>,
    cells: Option<usize>,
}

impl Bar {
    fn width(&self) -> usize {
        self.fixed_width.unwrap_or_else(|| {
            console::Term::stderr()
                .size_checked()
                .map_or(80, |(_, w)| usize::from(w))
        })
    }

    fn show(&mut self, s: &Status) {
        // a resized terminal gets a new layout at the next redraw
        let cells = bar_cells(self.width());
        if self.cells != Some(cells) {
            self.pb.set_style(style(cells));
            self.cells = Some(cells);
        }
        self.pb.set_position((s.fraction() * BAR_LEN as f64) as u64);
        self.pb.set_message(s.bar_message());
    }
}

#[derive(Debug)]
pub struct Progress {
    end_time: f64,
    /// Wall clock and simulated time and step when this process started running.
    start: Instant,
    start_time: f64,
    start_step: Option<u64>,
    last: Instant,
    every: Duration,
    bar: Option<Bar>,
    stop_noted: bool,
}

impl Progress {
    /// A bar when stderr is a terminal and not `quiet`; plain lines otherwise.
    /// `start_time`: the simulated time the run starts from (a restart's).
    pub fn new(end_time: f64, start_time: f64, quiet: bool) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| Bar {
            pb: ProgressBar::with_draw_target(Some(BAR_LEN), ProgressDrawTarget::stderr()),
            fixed_width: None,
            cells: None,
        });
        Self::with_bar(end_time, start_time, bar)
    }

    /// A bar drawn into `target`, `width` columns wide (tests: an in-memory terminal).
    pub fn on_target(
        end_time: f64,
        start_time: f64,
        target: ProgressDrawTarget,
        width: usize,
    ) -> Self {
        let bar = Bar {
            pb: ProgressBar::with_draw_target(Some(BAR_LEN), target),
            fixed_width: Some(width),
            cells: None,
        };
        Self::with_bar(end_time, start_time, Some(bar))
    }

    fn with_bar(end_time: f64, start_time: f64, bar: Option<Bar>) -> Self {
        let now = Instant::now();
        Self {
            end_time,
            start: now,
            start_time,
            start_step: None,
            // the first update draws at once
            last: now.checked_sub(PLAIN_EVERY).unwrap_or(now),
            every: if bar.is_some() {
                BAR_EVERY
            } else {
                PLAIN_EVERY
            },
            bar,
            stop_noted: false,
        }
    }

    /// Where the run stands, with the rate and ETA of this process's part of it.
    pub fn status(&mut self, step: u64, time: f64, dt: f64, energy_error: f64) -> Status {
        let wall = self.start.elapsed().as_secs_f64();
        self.status_at(wall, step, time, dt, energy_error)
    }

    /// `status` after `wall` seconds of this process's run.
    fn status_at(&mut self, wall: f64, step: u64, time: f64, dt: f64, energy_error: f64) -> Status {
        let first = *self.start_step.get_or_insert(step.saturating_sub(1));
        let done = time - self.start_time;
        let left = self.end_time - time;
        let eta = (done > 0.0 && wall > 0.0 && left.is_finite())
            .then(|| Duration::from_secs_f64((wall * left.max(0.0) / done).min(1e9)));
        Status {
            step,
            time,
            end_time: self.end_time,
            dt,
            energy_error,
            eta,
            rate: (step - first) as f64 / wall.max(1e-9),
        }
    }

    /// Called after every step with the step's number, the simulated time, the step
    /// just taken and the energy-balance error.
    pub fn update(&mut self, step: u64, time: f64, dt: f64, energy_error: f64) {
        self.note_stop();
        // step 0 is the initial record: nothing to say yet
        let now = Instant::now();
        if step == 0 || (self.start_step.is_some() && now.duration_since(self.last) < self.every) {
            return;
        }
        self.last = now;
        let s = self.status(step, time, dt, energy_error);
        match &mut self.bar {
            Some(bar) => bar.show(&s),
            None => eprintln!("{}", s.plain_line()),
        }
    }

    /// Once a stop is requested (SIGINT, SIGTERM), say what happens now.
    pub fn note_stop(&mut self) {
        if crash_master::stop::requested() && !self.stop_noted {
            self.stop_noted = true;
            self.message(
                "crash: stopping after this step: last frame, restart file, summary.json (interrupt again to quit at once)",
            );
        }
    }

    /// A line of its own (a warning), printed above the bar.
    pub fn message(&self, line: &str) {
        match &self.bar {
            Some(bar) => bar.pb.println(line),
            None => eprintln!("{line}"),
        }
    }

    /// The run has ended: the bar stays as last drawn, the next lines go below it.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.pb.abandon();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn status() -> Status {
        Status {
            step: 123_456,
            time: 1.234_567e-3,
            end_time: 5e-3,
            dt: 1.234e-7,
            energy_error: 1.5e-4,
            eta: Some(Duration::from_secs(75)),
            rate: 250.0,
        }
    }

    #[test]
    fn status_lines_carry_step_time_dt_energy_error_and_eta_without_escape_codes() {
        let s = status();
        for line in [s.plain_line(), s.bar_message()] {
            for part in [
                "123456",
                "1.2346e-3",
                "5.0000e-3",
                "1.2",
                "e-7",
                "e-4",
                "ETA 75s",
            ] {
                assert!(line.contains(part), "{part} in {line}");
            }
            assert!(!line.contains('\x1b'), "{line:?}");
        }
        assert!(s.plain_line().contains("(24.7%)"), "{}", s.plain_line());
    }

    /// On any terminal width the bar is one row: it never wraps onto a second line.
    #[test]
    fn the_bar_fits_any_terminal_width_on_one_row() {
        for width in [20u16, 40, 49, 50, 80, 99, 100, 145, 200] {
            let term = indicatif::InMemoryTerm::new(4, width);
            let mut p = Progress::on_target(
                5e-3,
                0.0,
                ProgressDrawTarget::term_like(Box::new(term.clone())),
                usize::from(width),
            );
            p.update(123_456, 1.234_567e-3, 1.234e-7, 1.5e-4);
            let warning = "crash: warning: step 12, t = 1.0e-4 s: a warning line";
            p.message(warning);
            p.update(123_457, 1.234_667e-3, 1.234e-7, 1.5e-4);
            let screen = term.contents();
            let rows: Vec<&str> = screen.lines().filter(|l| !l.trim().is_empty()).collect();
            // the warning above (a plain line: it wraps like any), the bar on one row
            let warning_rows = warning.len().div_ceil(usize::from(width));
            assert_eq!(rows.len(), warning_rows + 1, "width {width}: {screen:?}");
            assert!(
                rows[0].starts_with("crash: warning:"),
                "width {width}: {screen:?}"
            );
            let bar = rows[warning_rows];
            assert!(
                bar.chars().count() <= usize::from(width),
                "width {width}: {bar:?}"
            );
            assert!(bar.contains("24.7%"), "width {width}: {bar:?}");
            // 145 columns (where the hand-written line used to break) show it all
            if width >= 145 {
                assert!(
                    bar.starts_with('[') && bar.contains("energy error"),
                    "{bar:?}"
                );
            }
        }
    }

    #[test]
    fn eta_is_the_remaining_simulated_time_at_the_rate_so_far() {
        // restarted at t = 0.5 of 1.0 s: 0.25 s simulated in 10 s of wall time
        let mut p = Progress::with_bar(1.0, 0.5, None);
        let s = p.status_at(10.0, 100, 0.75, 1e-3, 0.0);
        assert_eq!(s.eta, Some(Duration::from_secs(10)));
        assert_eq!(s.fraction(), 0.75);
    }
}
