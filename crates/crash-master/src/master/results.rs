//! The result files' rows: each file is due at the start, whenever its interval's
//! multiple is crossed, and at the end. The rule depends on the step's two times only
//! (no counter), so a run resumed or rolled back to a checkpoint writes the rows it
//! wrote before, and every mode writes the same rows.

use super::{Master, TIME_EPS};
use crate::error::MasterError;
use crate::sink::{ResultRows, Sink};
use crash_link::WorkerLink;

/// Whether the step from `before` to `now` crosses a multiple of `interval` (> 0).
fn crossed(before: f64, now: f64, interval: f64) -> bool {
    let k = |t: f64| (t * (1.0 + TIME_EPS) / interval).floor();
    k(now) > k(before)
}

impl<L: WorkerLink> Master<'_, L> {
    /// Which of matsum, rcforc, nodout, spcforc have a row at `now` after a step from
    /// `before` (None: the start). Known before the step is sent, so the workers
    /// compute and send reactions and history nodes only for the steps that write them.
    pub(super) fn rows_due(&self, before: Option<f64>, now: f64) -> [bool; 4] {
        let end = now >= self.cfg.end_time * (1.0 - TIME_EPS);
        let r = &self.results;
        [r.matsum, r.rcforc, r.nodout, r.spcforc].map(|interval| {
            interval > 0.0
                && match before {
                    None => true,
                    Some(t0) => end || crossed(t0, now, interval),
                }
        })
    }

    /// Hand the due rows to the sink (`before`: the step's start time, None at the
    /// start of the run); the rcforc row not while the step's contact rows are held
    /// (held.rs writes it with them).
    pub(super) fn write_results(
        &mut self,
        sink: &mut dyn Sink,
        before: Option<f64>,
    ) -> Result<(), MasterError> {
        let (step, now) = (self.clock.step, self.clock.time);
        let [matsum, rcforc, nodout, spcforc] = self.rows_due(before, now);
        let rcforc = rcforc && self.held.is_none();
        let rows = ResultRows {
            matsum: matsum.then_some(&self.reports[..]),
            rcforc: rcforc.then_some(&self.contacts[..]),
            nodout: nodout.then_some(&self.probed[..]),
            spcforc: spcforc.then_some(&self.reports[..]),
        };
        if rows.matsum.is_none()
            && rows.rcforc.is_none()
            && rows.nodout.is_none()
            && rows.spcforc.is_none()
        {
            return Ok(());
        }
        sink.results(step, now, &rows).map_err(MasterError::sink)
    }
}

#[cfg(test)]
mod tests {
    use super::crossed;

    #[test]
    fn an_interval_is_crossed_once_per_multiple() {
        assert!(crossed(0.09, 0.1, 0.1));
        assert!(!crossed(0.1, 0.15, 0.1));
        assert!(crossed(0.15, 0.31, 0.1));
        // 3 * 0.1 in floating point lies below 0.3: it still counts as the multiple
        assert!(crossed(0.25, 0.1 + 0.1 + 0.1, 0.3 / 3.0));
    }
}
