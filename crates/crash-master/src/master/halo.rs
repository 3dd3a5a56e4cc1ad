//! The second half of a split step (issue 16 point 2): each holder's share of every
//! split body's report after the halo, merged into one report per body in its home's
//! report, and the element steps kept for the contact pass the next Step runs. The
//! halo comes back in the Step's reports when the holders exchanged their part states
//! directly (protocol v18, `halos`), else the master relays them in a `Halo` command
//! (`relay`: in process, `--no-direct-halo`, TLS, or after a direct exchange failed).

use super::Master;
use crate::error::MasterError;
use crash_core::partition::{merge_report, PartState, SplitFigures};
use crash_core::BodyReport;
use crash_link::{escape_peer, Command, LinkError, Reply, StepReport, WorkerLink};
use std::collections::BTreeMap;

impl<L: WorkerLink> Master<'_, L> {
    /// The second half of a step for the split groups: the halo replies (from the
    /// Step's reports when the holders exchanged directly, else from a relayed `Halo`),
    /// then every holder's share of each body's report merged into its home's report
    /// and the element steps kept for the contact pass the next Step (or an assembly)
    /// runs.
    pub(super) fn relay_split(
        &mut self,
        reps: &mut [StepReport],
        direct: bool,
    ) -> Result<(), MasterError> {
        if self.splits.is_empty() {
            return Ok(());
        }
        let nw = self.links.len();
        let group_of: BTreeMap<u32, usize> = self
            .splits
            .iter()
            .enumerate()
            .flat_map(|(k, s)| s.ids.iter().map(move |&id| (id, k)))
            .collect();
        let holds: Vec<Vec<usize>> = (0..nw)
            .map(|w| {
                (0..self.splits.len())
                    .filter(|&k| self.splits[k].workers.contains(&w))
                    .collect()
            })
            .collect();
        let replies = if direct {
            self.stats.halo_direct_steps += 1;
            self.halos(reps, &holds)?
        } else {
            self.stats.halo_relayed_steps += 1;
            self.relay(reps, &holds, &group_of)?
        };
        self.merge_halos(reps, replies, &group_of)
    }

    /// The halo replies of a step whose holders exchanged their part states directly
    /// (`StepReport::halo`). A direct exchange that failed turns it off for the rest
    /// of the run: the master rolls back to its last checkpoint (lib.rs) and relays.
    fn halos(
        &mut self,
        reps: &mut [StepReport],
        holds: &[Vec<usize>],
    ) -> Result<Vec<Vec<Reply>>, MasterError> {
        let nw = self.links.len();
        let mut counts = vec![0; nw];
        let mut got: Vec<Option<Reply>> = vec![None; nw];
        let mut lost = None;
        for w in (0..nw).filter(|&w| self.live[w] && !holds[w].is_empty()) {
            counts[w] = 1;
            match reps
                .get_mut(w)
                .and_then(|r| r.halo.take())
                .map(|h| (*h).into_reply())
            {
                Some(Ok(r)) => got[w] = Some(r),
                Some(Err(e)) => {
                    lost.get_or_insert((w, e));
                }
                None => return Err(self.bad_reply(w, "Step (no halo)")),
            }
        }
        if let Some((worker, reason)) = lost {
            self.direct_failed = true;
            return Err(MasterError::DirectHalo {
                step: self.clock.step,
                worker,
                reason: escape_peer(&reason),
            });
        }
        self.settle(&counts, vec![None; nw], |_, w| {
            got[w]
                .take()
                .ok_or_else(|| LinkError::Protocol("no halo".into()))
        })
    }

    /// The part states of the Step's reports relayed in a `Halo` to the other holders.
    fn relay(
        &mut self,
        reps: &mut [StepReport],
        holds: &[Vec<usize>],
        group_of: &BTreeMap<u32, usize>,
    ) -> Result<Vec<Vec<Reply>>, MasterError> {
        let nw = self.links.len();
        let from: Vec<Vec<PartState>> = reps
            .iter_mut()
            .map(|r| std::mem::take(&mut r.parts))
            .collect();
        // each holder gets the other holders' parts of its groups, in sender order; a
        // part moves to its last recipient (with two workers, its only one) and is
        // cloned for the others
        let mut imports: Vec<Vec<PartState>> = vec![Vec::new(); nw];
        for (v, parts) in from.into_iter().enumerate() {
            for p in parts {
                let Some(k) = group_of.get(&p.id) else {
                    continue;
                };
                let to: Vec<usize> = (0..nw)
                    .filter(|&w| w != v && holds[w].contains(k))
                    .collect();
                if let Some((&last, rest)) = to.split_last() {
                    for &w in rest {
                        imports[w].push(p.clone());
                    }
                    imports[last].push(p);
                }
            }
        }
        let cmds: Vec<Vec<Command>> = imports
            .into_iter()
            .zip(holds)
            .map(|(i, h)| {
                if h.is_empty() {
                    Vec::new()
                } else {
                    vec![Command::Halo(i)]
                }
            })
            .collect();
        self.exchange(cmds)
    }

    /// Every holder's share of each split body's report merged into its home's report
    /// (the element step and its element from the minimum over the holders), the
    /// element steps kept for the contact pass the next Step (or an assembly) runs.
    fn merge_halos(
        &mut self,
        reps: &mut [StepReport],
        replies: Vec<Vec<Reply>>,
        group_of: &BTreeMap<u32, usize>,
    ) -> Result<(), MasterError> {
        self.split_ns.clear();
        let mut figures = SplitFigures::default();
        let mut merged: BTreeMap<u32, BodyReport> = BTreeMap::new();
        for (w, r) in replies.into_iter().enumerate() {
            for reply in r {
                let Reply::Report(rep) = reply else {
                    return Err(self.bad_reply(w, "Halo"));
                };
                for d in &rep.part_dts.dts {
                    if !group_of.contains_key(&d.id) || d.dt.is_nan() {
                        return Err(
                            self.implausible(w, &format!("an element step of body {}", d.id))
                        );
                    }
                }
                for p in &rep.part_dts.pairs {
                    let same = |k: Option<&usize>| k.is_some() && k == group_of.get(&p.b);
                    let sane = p.c.is_finite() && p.c > 0.0 && p.max.iter().all(|m| *m >= 0.0);
                    if !same(group_of.get(&p.a)) || !sane {
                        let what = format!("closing-speed figures of bodies {} and {}", p.a, p.b);
                        return Err(self.implausible(w, &what));
                    }
                }
                figures.merge(rep.part_dts);
                for b in rep.bodies {
                    if !group_of.contains_key(&b.id) {
                        return Err(self.implausible(w, &format!("a share of body {}", b.id)));
                    }
                    let m = match merged.remove(&b.id) {
                        Some(a) => merge_report(a, b),
                        None => b,
                    };
                    merged.insert(m.id, m);
                }
                if let Some(r) = reps.get_mut(w) {
                    r.compute_ns += rep.compute_ns;
                }
                for g in rep.groups {
                    // each holder's time for groups.csv; the cost model takes the
                    // first holder's, under the home's report
                    self.split_ns.push((w, g.first, g.nanos));
                    let home = self
                        .splits
                        .get(group_of.get(&g.first).copied().unwrap_or(0));
                    if let Some(r) = home.and_then(|s| reps.get_mut(s.home())) {
                        if r.groups.iter().all(|x| x.first != g.first) {
                            r.groups.push(g);
                        }
                    }
                }
            }
        }
        // the closing-speed steps over all holders limit the merged stable steps (min:
        // the bits of one process's stage)
        for (id, limit) in figures.limits(self.contact.penalty) {
            if let Some(b) = merged.get_mut(&id) {
                b.stable_dt = b.stable_dt.min(limit);
            }
        }
        // the element steps in the groups' body order (the holders check it)
        let mut pending = SplitFigures {
            dts: Vec::with_capacity(figures.dts.len()),
            pairs: std::mem::take(&mut figures.pairs),
        };
        for s in &self.splits {
            let home = s.home();
            for id in &s.ids {
                let Some(d) = figures.dts.iter().find(|d| d.id == *id).copied() else {
                    return Err(self.implausible(home, &format!("no element step of body {id}")));
                };
                pending.dts.push(d);
                if let (Some(mut b), Some(r)) = (merged.remove(id), reps.get_mut(home)) {
                    // the shares' steps are limited alike by the element-form rule; the
                    // element that sets the element step is the minimum's over all holders
                    b.dt_element = d.element as usize;
                    r.bodies.push(b);
                }
            }
        }
        self.split_contact = pending;
        Ok(())
    }
}
