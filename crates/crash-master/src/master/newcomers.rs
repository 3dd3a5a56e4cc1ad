//! Workers that join after the start: at a step boundary each newcomer gets the next
//! index, the run's Setup and an empty layout, and the step's regroup places the groups
//! anew with it (cost-based, sticky: `assign` moves groups to it while the loads differ
//! by more than the balance tolerance). A rollback takes the newcomers that are ready
//! into its placement; with no worker left it waits for one (`rejoin_seconds`).

use super::{Master, Slot};
use crate::error::MasterError;
use crash_link::{Command, WorkerLink};
use std::time::Duration;

impl<L: WorkerLink> Master<'_, L> {
    /// Add the workers that attached (waiting up to `wait` for the first); how many.
    /// They hold nothing and have had no Setup yet.
    pub(super) fn admit(&mut self, wait: Duration) -> usize {
        let first = self.links.len();
        let Some(j) = self.joiner.as_mut() else {
            return 0;
        };
        let new = j.join(first, wait);
        let k = new.len();
        for l in new {
            self.fresh.push(self.links.len());
            self.links.push(Slot::Joined(l));
            self.live.push(true);
            self.layout.push(Vec::new());
        }
        k
    }

    /// At a step boundary: newcomers that are ready get the run's Setup and take part
    /// in this step's regroup.
    pub(super) fn admit_at_step(&mut self) -> Result<(), MasterError> {
        if self.joiner.is_none() {
            return Ok(());
        }
        let first = self.links.len();
        if self.admit(Duration::ZERO) == 0 {
            return Ok(());
        }
        let setup = self.setup();
        let cmds = (0..self.links.len())
            .map(|w| {
                if w >= first {
                    vec![Command::Setup(setup.clone())]
                } else {
                    Vec::new()
                }
            })
            .collect();
        self.expect_acks(cmds, "Setup")?;
        self.rebalance = true;
        Ok(())
    }

    /// No worker left: wait for a newcomer up to `rejoin_seconds`; whether one came.
    pub(super) fn wait_for_newcomer(&mut self, checkpoint: u64) -> bool {
        let s = self.opts.rejoin_seconds;
        if self.joiner.is_none() || s.is_nan() || s <= 0.0 {
            return false;
        }
        tracing::warn!(
            "step {}: every worker was lost; waiting up to {s:.0} s (--rejoin-timeout) for a worker to join, then the run goes back to its checkpoint of step {checkpoint} on it",
            self.clock.step
        );
        self.admit(Duration::from_secs_f64(s.min(1e9))) > 0
    }

    /// Log the newcomers that hold bodies now (once each).
    pub(super) fn announce(&mut self) {
        let worker_of = &self.worker_of;
        let info = &self.info;
        let step = self.clock.step;
        self.fresh.retain(|&w| {
            let ids: Vec<u32> = worker_of
                .iter()
                .zip(info)
                .filter(|(o, _)| **o == Some(w))
                .map(|(_, i)| i.id)
                .collect();
            if ids.is_empty() {
                return true;
            }
            tracing::info!(
                "step {step}: worker {w}, which joined during the run, received {} bodies ({ids:?})",
                ids.len()
            );
            false
        });
    }
}
