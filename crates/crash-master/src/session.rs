//! The time loop driven one step at a time by its caller: the same loop `run_with`
//! drives (and `crash run` and `crash-master` with it), for a caller that observes the
//! run between steps (the study reads the bodies of its in-process worker).

use crate::checkpoint::MasterCheckpoint;
use crate::error::MasterError;
use crate::input::{RunInput, RunOptions};
use crate::join::Newcomers;
use crate::master::Master;
use crate::sink::Sink;
use crate::stats::RunStats;
use crash_core::Clock;
use crash_link::WorkerLink;

/// A run in progress on `links`.
pub struct Session<'a, L: WorkerLink> {
    m: Master<'a, L>,
}

impl<L: WorkerLink> std::fmt::Debug for Session<'_, L> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("clock", &self.m.clock())
            .finish()
    }
}

impl<'a, L: WorkerLink> Session<'a, L> {
    /// Bodies onto the workers, forces of the initial configuration, the first frame
    /// (`resume`: the checkpoint's state instead, nothing written).
    pub fn start(
        input: RunInput,
        resume: Option<MasterCheckpoint>,
        links: &'a mut [L],
        sink: &mut dyn Sink,
        opts: &RunOptions,
    ) -> Result<Self, MasterError> {
        Self::start_with(input, resume, links, None, sink, opts)
    }

    /// As `start`, with workers that may join during the run (`join::Newcomers`).
    pub fn start_with(
        input: RunInput,
        resume: Option<MasterCheckpoint>,
        links: &'a mut [L],
        joiner: Option<&'a mut (dyn Newcomers<L> + 'a)>,
        sink: &mut dyn Sink,
        opts: &RunOptions,
    ) -> Result<Self, MasterError> {
        let mut m = Master::new(links, joiner, &input, *opts)?;
        let RunInput { bodies, briefs, .. } = input;
        let started = match resume {
            None => m.start(bodies, &briefs, sink),
            Some(state) => m.resume(state, bodies),
        };
        match started {
            Ok(()) => Ok(Self { m }),
            Err(e) => {
                m.shutdown(&format!("the run stopped: {e}"));
                Err(e)
            }
        }
    }

    /// Split the groups the rule picks (after the start; a run resumed from a
    /// checkpoint splits at its first regroup).
    pub fn split(&mut self) -> Result<(), MasterError> {
        self.m.split_groups()
    }

    pub fn finished(&self) -> bool {
        self.m.finished()
    }

    /// One global step.
    pub fn step(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        self.m.step(sink)
    }

    /// The state after the current step (gathered from the workers).
    pub fn checkpoint(&mut self) -> Result<MasterCheckpoint, MasterError> {
        self.m.checkpoint()
    }

    /// Write the contact rows a split group's pending contact pass holds back (running
    /// it first): before a checkpoint is written, every row up to its step is.
    pub fn settle_rows(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        self.m.settle_rows(sink)
    }

    /// After a fault ended the run: the held contact rows of the last complete step,
    /// when every holder's share of their pass came back (master/held.rs).
    pub fn rows_after_fault(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        self.m.rows_after_fault(sink)
    }

    /// Whether the last command found workers gone or frozen: `recover` can continue
    /// without them.
    pub fn has_lost(&self) -> bool {
        self.m.has_lost()
    }

    /// Drop the lost workers and roll the run back to `state` (a checkpoint of this
    /// run) on the others; then roll the sink back too (`Sink::rollback`).
    pub fn recover(&mut self, state: &MasterCheckpoint) -> Result<(), MasterError> {
        self.m.recover(state)
    }

    /// Whether the last fault reply can be checked by replaying its step on the other
    /// workers (`replay_fault`).
    pub fn can_replay_fault(&self) -> bool {
        self.m.can_replay_fault()
    }

    /// Set the worker that reported the last fault aside and roll the run back to
    /// `state` on the others: the replay tells a real fault from a made-up one.
    pub fn replay_fault(&mut self, state: &MasterCheckpoint) -> Result<(), MasterError> {
        self.m.replay_fault(state)
    }

    /// Workers dropped so far.
    pub fn recoveries(&self) -> u64 {
        self.m.recoveries()
    }

    /// The run's clock.
    pub fn clock(&self) -> Clock {
        self.m.clock()
    }

    /// The largest relative energy-balance error so far.
    pub fn max_energy_error(&self) -> f64 {
        self.m.max_energy_error()
    }

    /// Worker `w` (in-process ones can be read between steps).
    pub fn link(&self, w: usize) -> Option<&L> {
        self.m.link(w)
    }

    /// Steps done and time reached into the statistics (after a stop: the summary then
    /// says how far the run got).
    pub fn record_progress(&mut self) {
        self.m.record_progress();
    }

    pub fn stats(&self) -> &RunStats {
        &self.m.stats
    }

    pub(crate) fn stats_mut(&mut self) -> &mut RunStats {
        &mut self.m.stats
    }

    /// The final frame and the statistics (then `end`).
    pub fn finish(&mut self, sink: &mut dyn Sink) -> Result<RunStats, MasterError> {
        self.m.finish(sink)?;
        Ok(self.m.stats.clone())
    }

    /// Tell the workers to stop (after an error: why).
    pub fn end(&mut self, error: Option<&MasterError>) {
        match error {
            None => self.m.shutdown("the run is complete"),
            // a clean stop is no error: the caller says so in its own words
            Some(e @ MasterError::Interrupted { .. }) => {
                tracing::info!("{e}");
                self.m.shutdown(&format!("the run stopped: {e}"));
            }
            Some(e) => {
                tracing::error!("run stopped at step {}: {e}", self.m.clock().step);
                self.m.shutdown(&format!("the run stopped: {e}"));
            }
        }
    }
}
