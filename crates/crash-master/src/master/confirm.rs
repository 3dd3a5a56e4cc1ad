//! A fault told apart from a lie. The step is deterministic and a group computes the
//! same bits on any worker, so when a worker reports a fault and another live worker
//! exists (and a checkpoint), the run goes back to the checkpoint without the faulting
//! worker (it is set aside: it holds nothing and gets no command) and replays up to the
//! faulting step. The same fault at the same step (every field equal) is real: the run
//! ends with it as before. That step passing without it means the first worker lied or
//! is defective: it is dropped (`LinkError::Implausible`) and the run goes on. A run
//! without faults pays nothing: this starts only from a fault reply. Only runs that ask
//! for it (`RunOptions::confirm_faults`: crash-master) replay; in-process workers
//! cannot lie.

use super::Master;
use crate::checkpoint::MasterCheckpoint;
use crate::error::MasterError;
use crash_core::Fault;
use crash_link::{escape_peer, LinkError, WorkerLink};

/// A fault being replayed.
#[derive(Debug, Clone)]
pub(super) struct Suspect {
    /// The worker that reported it (set aside meanwhile).
    pub(super) worker: usize,
    /// The clock's step when the step that faulted began.
    step: u64,
    fault: Fault,
}

impl<L: WorkerLink> Master<'_, L> {
    /// Worker `w` replied with `f` (a fault naming its own bodies): remember it for a
    /// replay, or judge the replay's outcome. The run's error either way.
    pub(super) fn on_fault(&mut self, w: usize, f: Fault) -> MasterError {
        let step = self.clock.step;
        match self.suspect.take() {
            None => self.faulted = Some((w, f.clone())),
            Some(s) => {
                // back in the run, to be told to stop with the others
                self.live[s.worker] = true;
                if s.step == step && s.fault == f {
                    tracing::warn!(
                        "step {step}: the fault worker {} reported recurred on worker {w} ({}) in the replay: it is real",
                        s.worker,
                        self.links[w].peer()
                    );
                } else {
                    // another fault in the replay: not replayed again (documented)
                    tracing::warn!(
                        "step {step}: the replay of worker {}'s fault (step {}) met another fault on worker {w}",
                        s.worker,
                        s.step
                    );
                }
            }
        }
        MasterError::Fault(f)
    }

    /// Whether the last fault can be checked by a replay: asked for, and another worker
    /// is in the run.
    pub(crate) fn can_replay_fault(&self) -> bool {
        self.opts.confirm_faults
            && self
                .faulted
                .as_ref()
                .is_some_and(|(w, _)| (0..self.links.len()).any(|x| x != *w && self.live[x]))
    }

    /// Set the faulting worker aside and roll the others back to `ck`.
    pub(crate) fn replay_fault(&mut self, ck: &MasterCheckpoint) -> Result<(), MasterError> {
        let Some((w, fault)) = self.faulted.take() else {
            return Ok(());
        };
        tracing::warn!(
            "step {}: worker {w} ({}) reported a fault: {}; the run goes back to its checkpoint of step {} and replays it on the other workers to tell a real fault from a made-up one",
            self.clock.step,
            self.links[w].peer(),
            escape_peer(&fault.to_string()),
            ck.clock.step
        );
        self.live[w] = false;
        self.suspect = Some(Suspect {
            worker: w,
            step: self.clock.step,
            fault,
        });
        self.recover(ck)
    }

    /// The step that faulted (clock step `at`) passed in the replay without the fault:
    /// the worker that reported it is dropped as an implausible one.
    pub(super) fn replayed_without_fault(&mut self, at: u64) {
        if self.suspect.as_ref().is_none_or(|s| s.step != at) {
            return;
        }
        let Some(s) = self.suspect.take() else { return };
        let e = LinkError::Implausible(escape_peer(&format!(
            "a fault that did not recur when its step was replayed on the other workers ({})",
            s.fault
        )));
        tracing::warn!(
            "step {}: lost worker {} ({}): {e}; the run goes on without it",
            self.clock.step,
            s.worker,
            self.links[s.worker].peer()
        );
        self.links[s.worker].abandon(&format!(
            "this worker was dropped from the run at step {}: {e}",
            self.clock.step
        ));
        self.recoveries += 1;
    }
}
