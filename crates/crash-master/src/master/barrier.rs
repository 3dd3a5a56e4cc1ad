//! The barrier: commands out to every worker (all sent before any wait, so remote
//! workers compute concurrently), every reply back; reports merged in body-id order.

use super::Master;
use crate::error::MasterError;
use crate::input::CostModel;
use crash_core::contact::PairStats;
use crash_core::{BodyReport, Clock, Fault};
use crash_link::{escape_peer, Command, GroupTime, LinkError, Reply, StepReport, WorkerLink};

/// Weight of one step's measured group time in a body's cost average. One step's time
/// jitters by tens of percent on a shared VM (wake-ups, a neighbour's build); a window
/// of ~32 steps keeps placement from balancing on noise yet follows an impact (which
/// changes a group's cost over hundreds of steps) well within the 500-step rebalance.
const COST_SMOOTHING: f64 = 1.0 / 32.0;

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

    /// Send every live link its commands, then collect the replies (in order; a worker
    /// dropped earlier gets nothing and answers nothing). Every live worker's replies
    /// are read even when another fails, so the survivors' streams stay in step for a
    /// rollback: workers that are gone or frozen are recorded in `lost` and the first
    /// such loss is returned. Otherwise a refused command is returned; of several
    /// faults the one of the group with the smallest body id wins (the same in every
    /// placement).
    pub(super) fn exchange(
        &mut self,
        cmds: Vec<Vec<Command>>,
    ) -> Result<Vec<Vec<Reply>>, MasterError> {
        let counts: Vec<usize> = cmds.iter().map(Vec::len).collect();
        let mut failed: Vec<Option<LinkError>> = vec![None; counts.len()];
        for (w, list) in cmds.into_iter().enumerate() {
            if !self.live[w] {
                continue;
            }
            for c in list {
                if let Err(e) = self.links[w].send(c) {
                    failed[w] = Some(e);
                    break;
                }
            }
        }
        self.settle(&counts, failed, |m, w| m.links[w].recv())
    }

    /// The replies of an exchange, `counts[w]` from worker w by `next` (unless
    /// `failed[w]`), judged as `exchange` says.
    pub(super) fn settle(
        &mut self,
        counts: &[usize],
        mut failed: Vec<Option<LinkError>>,
        mut next: impl FnMut(&mut Self, usize) -> Result<Reply, LinkError>,
    ) -> Result<Vec<Vec<Reply>>, MasterError> {
        self.faulted = None;
        self.fault_shares = None;
        let mut out = Vec::with_capacity(counts.len());
        let mut fault: Option<(u32, Fault, usize)> = None;
        // each fault's share of a pending split contact pass (held.rs: `rows_after_fault`)
        let mut shares: Vec<Option<Vec<PairStats>>> = vec![None; counts.len()];
        let mut refused: Option<(usize, String)> = None;
        for (w, &count) in counts.iter().enumerate() {
            let mut replies = Vec::with_capacity(count);
            if self.live[w] && failed[w].is_none() {
                for _ in 0..count {
                    match next(self, w) {
                        Err(e) => {
                            failed[w] = Some(e);
                            break;
                        }
                        Ok(Reply::Error(reason)) => {
                            refused.get_or_insert((w, reason));
                        }
                        Ok(Reply::Fault {
                            group_first,
                            fault: f,
                            split_contacts,
                        }) => {
                            shares[w] = split_contacts;
                            // plausible.rs: a lie drops the worker (as a loss)
                            if let Err(what) = self.check_fault(w, group_first, &f) {
                                failed[w] = Some(LinkError::Implausible(escape_peer(&what)));
                                break;
                            }
                            // the group with the smallest body first, then the fault
                            // one process would name (a split group's holders each
                            // report the first of their own parts')
                            let key = (group_first, f.order());
                            if fault.as_ref().is_none_or(|(g, p, _)| key < (*g, p.order())) {
                                fault = Some((group_first, f, w));
                            }
                        }
                        Ok(r) => replies.push(r),
                    }
                }
            }
            out.push(replies);
        }
        let mut first: Option<MasterError> = None;
        for (w, e) in failed.into_iter().enumerate() {
            if let Some(e) = e {
                let err = self.worker_error(w, e.clone());
                if e.is_loss() {
                    self.lost.push((w, e));
                }
                first.get_or_insert(err);
            }
        }
        if let Some(e) = first {
            return Err(e);
        }
        if let Some((w, reason)) = refused {
            return Err(self.worker_error(w, LinkError::Refused(reason)));
        }
        if let Some((_, f, w)) = fault {
            // the others' shares are in their reports (the replies are dropped here)
            for (s, replies) in shares.iter_mut().zip(&mut out) {
                if let Some(Reply::Report(rep)) = replies.first_mut() {
                    *s = Some(std::mem::take(&mut rep.split_contacts));
                }
            }
            self.fault_shares = Some(shares);
            // confirm.rs: replayed elsewhere before it is believed (with checkpoints)
            return Err(self.on_fault(w, f));
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
        let cmds = (0..nw)
            .map(|w| {
                if self.live[w] {
                    vec![cmd()]
                } else {
                    Vec::new()
                }
            })
            .collect();
        let replies = self.exchange(cmds)?;
        let mut reps = Vec::with_capacity(nw);
        for (w, mut r) in replies.into_iter().enumerate() {
            match r.pop() {
                Some(Reply::Report(rep)) => reps.push(rep),
                // a dropped worker holds nothing
                None if !self.live[w] => reps.push(StepReport::default()),
                _ => return Err(self.bad_reply(w, what)),
            }
        }
        Ok(reps)
    }

    /// Reports of all workers into one list in body-id order.
    /// Take the reports of the start (`step` None) or of the step of length h from clock
    /// `step = Some((clock, h))`.
    pub(super) fn gather(
        &mut self,
        reps: Vec<StepReport>,
        step: Option<(Clock, f64)>,
    ) -> Result<(), MasterError> {
        // In place, without allocating per step: each report lands in its body's slot;
        // `seen` (kept between steps) marks the slots filled by this step.
        let n = self.info.len();
        self.contacts.clear();
        self.probed.clear();
        if self.reports.len() != n {
            self.reports.clear();
            self.reports
                .extend(self.info.iter().map(|i| BodyReport::empty(i.id)));
        }
        self.seen.clear();
        self.seen.resize(n, false);
        self.group_ns.clear();
        self.group_ns.resize(n, 0);
        // the holders' times of split groups come with the Halo (split.rs)
        if self.splits.is_empty() {
            self.split_ns.clear();
        }
        // one pass for every worker's count (one pass per worker cost 0.7 ms a step
        // with 10 000 bodies on 64 workers)
        let mut held = vec![0usize; reps.len()];
        for w in self.worker_of.iter().flatten() {
            if let Some(c) = held.get_mut(*w) {
                *c += 1;
            }
        }
        let mut count = 0;
        for (w, rep) in reps.into_iter().enumerate() {
            // marks `seen` for the worker's bodies (plausible.rs)
            if let Err(what) = self.check_report(w, held[w], &rep) {
                return Err(self.implausible(w, &what));
            }
            // by reference: one copy of each report into its slot (moving them out of
            // the vector copied each twice)
            for r in &rep.bodies {
                if let Some(i) = self.index(r.id) {
                    self.reports[i] = *r;
                    count += 1;
                }
            }
            self.account(&rep.groups);
            self.contacts.extend_from_slice(&rep.contacts);
            for p in rep.probes {
                let key = (p.body, p.node);
                let h = &self.results.history;
                match h.binary_search_by_key(&key, |h| (h.0, h.1)) {
                    Ok(k) => self.probed.push((h[k].2, p)),
                    Err(_) => {
                        return Err(self.worker_error(
                            w,
                            LinkError::Protocol(format!(
                                "unexpected history node {} of body {}",
                                p.node, p.body
                            )),
                        ))
                    }
                }
            }
        }
        if count != n {
            return Err(MasterError::Incomplete {
                step: self.clock.step,
                what: "reports",
                got: count,
                expected: n,
            });
        }
        self.contacts.sort_by_key(|c| (c.a, c.b));
        // the contact work on kinematic bodies, in pair order as the driver adds it
        if let Some((at, h)) = step {
            self.kinematic.settle(&at, h);
        }
        self.kinematic.add(&self.contacts);
        self.kinematic.apply(&mut self.reports);
        self.probed.sort_by_key(|p| (p.1.body, p.1.node));
        Ok(())
    }

    /// Measured group times shared among members by their estimated cost (EMA over
    /// about `1 / COST_SMOOTHING` steps).
    fn account(&mut self, groups: &[GroupTime]) {
        for g in groups {
            if let Some(i) = self.index(g.first) {
                self.group_ns[i] = g.nanos;
            }
        }
        if self.opts.cost != CostModel::Measured {
            return;
        }
        for g in groups {
            // the worker's groups are the MEIM groups of this step
            let Some(k) = self.meim.group_of(g.first) else {
                continue;
            };
            let members = self.meim.group(k);
            let total: f64 = members
                .iter()
                .filter_map(|&id| self.index(id))
                .map(|b| self.info[b].estimate)
                .sum();
            for &id in members {
                let Some(b) = self.index(id) else { continue };
                let t = g.nanos as f64 * self.info[b].estimate / total;
                self.measured[b] = Some(match self.measured[b] {
                    Some(old) => old + COST_SMOOTHING * (t - old),
                    None => t,
                });
            }
        }
    }
}
