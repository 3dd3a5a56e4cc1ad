//! Contact rows held for a split group's pending contact pass. A split group's
//! contact pass of step n runs on its holders at the start of step n + 1 (or in a
//! `Contact` before an assembly: split.rs), so its statistics arrive one exchange
//! after the step's other figures. The step's contacts.csv rows and its rcforc row
//! wait for them: each holder books the pushes of the slave nodes it owns, the master
//! merges the shares per pair (`PairStats::merge`: exact sums, the bits of one
//! process) with the unsplit groups' statistics, and writes the step's rows then,
//! before any row of a later step and before a checkpoint is written.

use super::plausible::stats_finite;
use super::Master;
use crate::error::MasterError;
use crate::sink::{ResultRows, Sink};
use crash_core::contact::PairStats;
use crash_link::{StepReport, WorkerLink};

/// A step's contact rows waiting for its split groups' statistics.
#[derive(Debug, Clone)]
pub(super) struct HeldRows {
    step: u64,
    time: f64,
    /// The unsplit groups' statistics of the step.
    contacts: Vec<PairStats>,
    /// The step writes an rcforc row.
    rcforc: bool,
    /// The split groups' statistics, merged over the holders (None: the pass is still
    /// pending).
    split: Option<Vec<PairStats>>,
}

impl<L: WorkerLink> Master<'_, L> {
    /// Whether the step just gathered left a split group's contact pass pending: its
    /// contact rows are then held (`hold_rows`) rather than written.
    pub(super) fn rows_wait(&self) -> bool {
        !self.split_contact.is_empty()
    }

    /// Hold the rows of the step just gathered (`rcforc`: it writes an rcforc row).
    pub(super) fn hold_rows(&mut self, rcforc: bool) {
        self.held = Some(HeldRows {
            step: self.clock.step,
            time: self.clock.time,
            contacts: self.contacts.clone(),
            rcforc,
            split: None,
        });
    }

    /// The holders' shares of the pending pass's statistics, from the replies that ran
    /// it (a Step's or a Contact's, by worker): checked, merged per pair. Rows are held
    /// exactly while a pass is pending, so replies that come while rows are held are
    /// the ones that ran it.
    pub(super) fn take_split_stats(&mut self, reps: &mut [StepReport]) -> Result<(), MasterError> {
        let shares = reps
            .iter_mut()
            .map(|r| std::mem::take(&mut r.split_contacts));
        self.merge_split_shares(shares.enumerate())
    }

    /// `take_split_stats` of the shares by worker.
    fn merge_split_shares(
        &mut self,
        shares: impl Iterator<Item = (usize, Vec<PairStats>)>,
    ) -> Result<(), MasterError> {
        let merged = self.merged_split_shares(shares)?;
        if let Some(h) = self.held.as_mut().filter(|h| h.split.is_none()) {
            h.split = Some(merged);
        }
        Ok(())
    }

    /// The holders' shares of a split pass's statistics (by worker), checked and
    /// merged per pair.
    pub(super) fn merged_split_shares(
        &mut self,
        shares: impl Iterator<Item = (usize, Vec<PairStats>)>,
    ) -> Result<Vec<PairStats>, MasterError> {
        let mut merged: Vec<PairStats> = Vec::new();
        for (w, share) in shares {
            for c in &share {
                // a split group holds no kinematic body: no loads on one
                let no_kin = c.kin_a.is_empty() && c.kin_b.is_empty();
                let held = self.holds_part(w, c.a) && self.holds_part(w, c.b);
                if !(stats_finite(c) && no_kin && c.a <= c.b && held) {
                    let what = format!("split contact statistics of the pair ({}, {})", c.a, c.b);
                    return Err(self.implausible(w, &what));
                }
            }
            PairStats::merge_sorted(&mut merged, &share);
        }
        Ok(merged)
    }

    /// Write the held rows once their split statistics are in.
    pub(super) fn release_rows(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        let Some(h) = self.held.take_if(|h| h.split.is_some()) else {
            return Ok(());
        };
        let mut rows = h.contacts;
        rows.extend(h.split.unwrap_or_default());
        rows.sort_by_key(|c| (c.a, c.b));
        sink.contact_stats(h.step, h.time, &rows)
            .map_err(MasterError::sink)?;
        if h.rcforc {
            let only = ResultRows {
                matsum: None,
                rcforc: Some(&rows),
                nodout: None,
                spcforc: None,
            };
            sink.results(h.step, h.time, &only)
                .map_err(MasterError::sink)?;
        }
        Ok(())
    }

    /// The run ends with a fault: write the held rows of the last complete step if
    /// their statistics are in. They are when the fault came after the exchange that
    /// ran the pending pass (in the Halo exchange, which checks the moves over the
    /// parts), or with it when every holder's share came back, from the fault or from
    /// the others' reports (barrier.rs). Otherwise the rows stay unwritten: a holder's
    /// pass did not run to its end.
    pub(crate) fn rows_after_fault(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        let shares = self.fault_shares.take();
        if self.held.as_ref().is_some_and(|h| h.split.is_none()) {
            let Some(shares) = shares else {
                return Ok(());
            };
            if (0..shares.len()).any(|w| self.holds_parts(w) && shares[w].is_none()) {
                return Ok(());
            }
            let shares = shares.into_iter().map(Option::unwrap_or_default);
            self.merge_split_shares(shares.enumerate())?;
        }
        self.release_rows(sink)
    }

    /// Write the held rows now: run the pending contact pass first if it still is
    /// (before a checkpoint is written, and at the end of the run).
    pub(crate) fn settle_rows(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        if self.held.as_ref().is_some_and(|h| h.split.is_none()) {
            self.flush_split_contact()?;
        }
        self.release_rows(sink)
    }
}
