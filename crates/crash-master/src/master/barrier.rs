//! The barrier: commands out to every worker (all sent before any wait, so remote
//! workers compute concurrently), every reply back; reports merged in body-id order.

use super::Master;
use crate::error::MasterError;
use crate::input::CostModel;
use crash_core::{BodyReport, Fault};
use crash_link::{Command, GroupTime, LinkError, Reply, StepReport, WorkerLink};

impl<L: WorkerLink> Master<'_, L> {
    pub(super) fn worker_error(&self, w: usize, e: LinkError) -> MasterError {
        MasterError::Worker {
            step: self.clock.step,
            worker: w,
            peer: self.links[w].peer(),
            reason: e,
        }
    }

    pub(super) fn bad_reply(&self, w: usize, what: &str) -> MasterError {
        self.worker_error(
            w,
            LinkError::Protocol(format!("unexpected reply to {what}")),
        )
    }

    /// Send every link its commands, then collect the replies (in order). Errors and
    /// faults end the exchange; of several faults the one of the group with the
    /// smallest body id wins (the same in every placement).
    pub(super) fn exchange(
        &mut self,
        cmds: Vec<Vec<Command>>,
    ) -> Result<Vec<Vec<Reply>>, MasterError> {
        let counts: Vec<usize> = cmds.iter().map(Vec::len).collect();
        for (w, list) in cmds.into_iter().enumerate() {
            for c in list {
                self.links[w].send(c).map_err(|e| self.worker_error(w, e))?;
            }
        }
        let mut out = Vec::with_capacity(counts.len());
        let mut fault: Option<(u32, Fault)> = None;
        for (w, &count) in counts.iter().enumerate() {
            let mut replies = Vec::with_capacity(count);
            for _ in 0..count {
                match self.links[w].recv().map_err(|e| self.worker_error(w, e))? {
                    Reply::Error(reason) => {
                        return Err(self.worker_error(w, LinkError::Refused(reason)))
                    }
                    Reply::Fault {
                        group_first,
                        fault: f,
                    } => {
                        if fault.as_ref().is_none_or(|(g, _)| group_first < *g) {
                            fault = Some((group_first, f));
                        }
                    }
                    r => replies.push(r),
                }
            }
            out.push(replies);
        }
        if let Some((_, f)) = fault {
            return Err(MasterError::Fault(f));
        }
        Ok(out)
    }

    /// One command to every worker, each answered by a report.
    pub(super) fn reports_of(
        &mut self,
        cmd: impl Fn() -> Command,
        what: &str,
    ) -> Result<Vec<StepReport>, MasterError> {
        let nw = self.links.len();
        let replies = self.exchange((0..nw).map(|_| vec![cmd()]).collect())?;
        let mut reps = Vec::with_capacity(nw);
        for (w, mut r) in replies.into_iter().enumerate() {
            match r.pop() {
                Some(Reply::Report(rep)) => reps.push(rep),
                _ => return Err(self.bad_reply(w, what)),
            }
        }
        Ok(reps)
    }

    /// Reports of all workers into one list in body-id order.
    pub(super) fn gather(&mut self, reps: Vec<StepReport>) -> Result<(), MasterError> {
        let n = self.info.len();
        self.reports.clear();
        self.contacts.clear();
        self.group_ns.clear();
        let mut slot: Vec<Option<BodyReport>> = vec![None; n];
        let mut count = 0;
        for (w, rep) in reps.into_iter().enumerate() {
            for r in rep.bodies {
                match self.index(r.id) {
                    Some(i) if slot[i].is_none() && self.worker_of[i] == Some(w) => {
                        slot[i] = Some(r);
                        count += 1;
                    }
                    _ => {
                        return Err(self.worker_error(
                            w,
                            LinkError::Protocol(format!("unexpected report of body {}", r.id)),
                        ))
                    }
                }
            }
            self.account(&rep.groups);
            self.contacts.extend_from_slice(&rep.contacts);
        }
        if count != n {
            return Err(MasterError::Incomplete {
                step: self.clock.step,
                what: "reports",
                got: count,
                expected: n,
            });
        }
        self.reports.extend(slot.into_iter().flatten());
        self.contacts.sort_by_key(|c| (c.a, c.b));
        // the contact work on kinematic bodies, in pair order as the driver adds it
        self.kinematic.add(&self.contacts);
        self.kinematic.apply(&mut self.reports);
        Ok(())
    }

    /// Measured group times shared among members by their estimated cost (EMA).
    fn account(&mut self, groups: &[GroupTime]) {
        for g in groups {
            self.group_ns.insert(g.first, g.nanos);
        }
        if self.opts.cost != CostModel::Measured {
            return;
        }
        for g in groups {
            // the worker's groups are the MEIM groups of this step
            let Some(k) = self.meim.group_of(g.first) else {
                continue;
            };
            let members: Vec<usize> = self
                .meim
                .group(k)
                .iter()
                .filter_map(|&id| self.index(id))
                .collect();
            let total: f64 = members.iter().map(|&b| self.info[b].estimate).sum();
            for &b in &members {
                let t = g.nanos as f64 * self.info[b].estimate / total;
                self.measured[b] = Some(match self.measured[b] {
                    Some(old) => 0.8 * old + 0.2 * t,
                    None => t,
                });
            }
        }
    }
}
