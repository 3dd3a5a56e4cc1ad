//! Losing a worker: the workers an exchange found gone or frozen are dropped, every
//! survivor forgets its bodies (`Reset`), the loop's state and every body's state come
//! back from the last checkpoint, the groups are placed on the survivors (sticky: a
//! survivor keeps its own groups, the lost worker's go where the load is least) and the
//! run continues from the checkpoint's step. The step is deterministic and a group
//! computes the same bits on any worker, so the replayed steps give the bits they gave
//! before and the run ends with the hash of a run without fault. A survivor that lacks a
//! body's definition gets it built anew from the scene; the others get the state only.
//! Workers that joined meanwhile take part in the placement (newcomers.rs); with no
//! worker left the master waits for one up to `rejoin_seconds`.

use super::Master;
use crate::checkpoint::MasterCheckpoint;
use crate::error::MasterError;
use crash_link::{BodyLoad, Command, WorkerLink};

impl<L: WorkerLink> Master<'_, L> {
    /// Whether the last exchange found workers gone or frozen (a rollback can go on
    /// without them).
    pub(crate) fn has_lost(&self) -> bool {
        !self.lost.is_empty()
    }

    /// Drop the lost workers and roll the survivors back to `ck` (again if another
    /// worker is lost meanwhile). With no survivor: `MasterError::NoWorkers`.
    pub(crate) fn recover(&mut self, ck: &MasterCheckpoint) -> Result<(), MasterError> {
        let at = self.clock.step;
        loop {
            for (w, e) in std::mem::take(&mut self.lost) {
                if !self.live[w] {
                    continue;
                }
                tracing::warn!(
                    "step {at}: lost worker {w} ({}): {e}; the run goes back to its checkpoint of step {} on the other workers",
                    self.links[w].peer(),
                    ck.clock.step
                );
                self.links[w].abandon(&format!(
                    "this worker was dropped from the run at step {at}: {e}"
                ));
                self.live[w] = false;
                self.recoveries += 1;
            }
            // newcomers that are ready take part in the placement
            self.admit(std::time::Duration::ZERO);
            if self.live_count() == 0 && !self.wait_for_newcomer(ck.clock.step) {
                return Err(MasterError::NoWorkers {
                    step: at,
                    checkpoint: ck.clock.step,
                });
            }
            match self.roll_back(ck) {
                Ok(()) => return Ok(()),
                // another worker went during the rollback: drop it too, start over
                Err(_) if self.has_lost() => continue,
                Err(e) => return Err(e),
            }
        }
    }

    fn roll_back(&mut self, ck: &MasterCheckpoint) -> Result<(), MasterError> {
        let nw = self.links.len();
        self.expect_acks((0..nw).map(|_| vec![Command::Reset]).collect(), "Reset")?;
        // a Reset forgets the split groups too; the rule splits again at the next regroup
        self.splits.clear();
        // a split planned at the start and not made yet: the workers forgot its groups
        self.planned.clear();
        self.split_contact = Default::default();
        self.held = None;
        self.split_now = None;
        self.restore_loop(ck);
        let placement = self.place_all();
        // per body: does its new worker lack the definition?
        let lacks: Vec<bool> = self
            .info
            .iter()
            .zip(&placement)
            .map(|(inf, &w)| !self.links[w].has_definition(inf.id))
            .collect();
        let mut source = self.source.take();
        let mut states = ck.states.iter();
        let mut index = 0;
        let loaded = self.load_all(&placement, |id| {
            let state = states
                .next()
                .filter(|(sid, _)| *sid == id)
                .map(|(_, s)| s.clone())
                .ok_or_else(|| {
                    MasterError::Input(format!("the checkpoint has no state of body {id}"))
                })?;
            let def = if lacks.get(index).copied().unwrap_or(true) {
                let src = source.as_mut().ok_or_else(|| {
                    MasterError::Input(format!("no definition of body {id} to rebuild"))
                })?;
                Some(src.take(id)?.def)
            } else {
                None
            };
            index += 1;
            Ok(BodyLoad { id, def, state })
        });
        self.source = source;
        loaded?;
        self.announce();
        Ok(())
    }
}
