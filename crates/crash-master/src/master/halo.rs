//! The second half of a split step (issue 16 point 2): each holder's share of every
//! split body's report after the halo, merged into one report per body in its home's
//! report, and the element steps kept for the contact pass the next Step runs. The
//! halo comes back in the Step's reports when the holders exchanged their part states
//! directly (protocol v18, `halos`), else the master relays them in a `Halo` command
//! (`relay`: in process, `--no-direct-halo`, TLS, or after a direct exchange failed).

use super::Master;
use crate::error::MasterError;
use crash_core::partition::{merge_report, PartDt, PartState, SplitFigures};
use crash_core::BodyReport;
use crash_link::{escape_peer, Command, LinkError, Reply, StepReport, WorkerLink};
use std::time::Instant;

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
        let group_of = SplitIndex::of(self.splits.iter().map(|s| &s.ids[..]));
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
        let merging = Instant::now();
        let merged = self.merge_halos(reps, replies, &group_of);
        self.merge_ns += merging.elapsed().as_nanos() as u64;
        merged
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
        group_of: &SplitIndex,
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
                let Some(k) = group_of.group(p.id) else {
                    continue;
                };
                let to: Vec<usize> = (0..nw)
                    .filter(|&w| w != v && holds[w].contains(&k))
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
        group_of: &SplitIndex,
    ) -> Result<(), MasterError> {
        self.split_ns.clear();
        let mut shares = Vec::with_capacity(replies.len());
        // each body's merged report at its place in the groups' body order
        let mut merged: Vec<Option<BodyReport>> = vec![None; group_of.len()];
        for (w, r) in replies.into_iter().enumerate() {
            for reply in r {
                let Reply::Report(rep) = reply else {
                    return Err(self.bad_reply(w, "Halo"));
                };
                for d in &rep.part_dts.dts {
                    if group_of.group(d.id).is_none() || d.dt.is_nan() {
                        return Err(
                            self.implausible(w, &format!("an element step of body {}", d.id))
                        );
                    }
                }
                for p in &rep.part_dts.pairs {
                    let sane = p.c.is_finite() && p.c > 0.0 && p.max.iter().all(|m| *m >= 0.0);
                    let ka = group_of.group(p.a);
                    if ka.is_none() || ka != group_of.group(p.b) || !sane {
                        let what = format!("closing-speed figures of bodies {} and {}", p.a, p.b);
                        return Err(self.implausible(w, &what));
                    }
                }
                shares.push(rep.part_dts);
                for b in rep.bodies {
                    let Some(at) = group_of.place(b.id) else {
                        return Err(self.implausible(w, &format!("a share of body {}", b.id)));
                    };
                    let m = &mut merged[at];
                    *m = Some(m.map_or(b, |a| merge_report(a, b)));
                }
                if let Some(r) = reps.get_mut(w) {
                    r.compute_ns += rep.compute_ns;
                }
                for g in rep.groups {
                    // each holder's time for groups.csv; the cost model takes the
                    // first holder's, under the home's report
                    self.split_ns.push((w, g.first, g.nanos));
                    let home = self.splits.get(group_of.group(g.first).unwrap_or(0));
                    if let Some(r) = home.and_then(|s| reps.get_mut(s.home())) {
                        if r.groups.iter().all(|x| x.first != g.first) {
                            r.groups.push(g);
                        }
                    }
                }
            }
        }
        let mut figures = SplitFigures::merge_all(shares);
        // the closing-speed steps over all holders limit the merged stable steps (min:
        // the bits of one process's stage)
        for (id, limit) in figures.limits(self.contact.penalty) {
            if let Some(b) = group_of.place(id).and_then(|at| merged[at].as_mut()) {
                b.stable_dt = b.stable_dt.min(limit);
            }
        }
        // the element steps in the groups' body order (the holders check it)
        let mut dts: Vec<Option<PartDt>> = vec![None; group_of.len()];
        for d in std::mem::take(&mut figures.dts) {
            if let Some(at) = group_of.place(d.id) {
                dts[at] = Some(d);
            }
        }
        let mut pending = SplitFigures {
            dts: Vec::with_capacity(dts.len()),
            pairs: std::mem::take(&mut figures.pairs),
        };
        let mut at = 0;
        for s in &self.splits {
            let home = s.home();
            for id in &s.ids {
                let Some(d) = dts[at] else {
                    return Err(self.implausible(home, &format!("no element step of body {id}")));
                };
                pending.dts.push(d);
                if let (Some(mut b), Some(r)) = (merged[at].take(), reps.get_mut(home)) {
                    // the shares' steps are limited alike by the element-form rule; the
                    // element that sets the element step is the minimum's over all holders
                    b.dt_element = d.element as usize;
                    r.bodies.push(b);
                }
                at += 1;
            }
        }
        self.split_contact = pending;
        Ok(())
    }
}

/// The split groups' bodies by id: each one's group (its index in `Master::splits`)
/// and its place in the groups' body order (group by group, each in its own order),
/// looked up by binary search; built once per step, with no map to allocate.
pub(super) struct SplitIndex {
    /// (body id, group, place), sorted by id.
    by_id: Vec<(u32, usize, usize)>,
}

impl SplitIndex {
    pub(super) fn of<'s>(groups: impl Iterator<Item = &'s [u32]>) -> Self {
        let mut by_id: Vec<(u32, usize, usize)> = Vec::new();
        for (k, ids) in groups.enumerate() {
            for &id in ids {
                by_id.push((id, k, by_id.len()));
            }
        }
        by_id.sort_unstable_by_key(|e| e.0);
        Self { by_id }
    }

    /// How many split bodies.
    pub(super) fn len(&self) -> usize {
        self.by_id.len()
    }

    fn find(&self, id: u32) -> Option<&(u32, usize, usize)> {
        self.by_id
            .binary_search_by_key(&id, |e| e.0)
            .ok()
            .map(|i| &self.by_id[i])
    }

    /// The group of body `id` (None: in no split group).
    pub(super) fn group(&self, id: u32) -> Option<usize> {
        self.find(id).map(|e| e.1)
    }

    /// The place of body `id` in the groups' body order.
    pub(super) fn place(&self, id: u32) -> Option<usize> {
        self.find(id).map(|e| e.2)
    }
}

#[cfg(test)]
mod tests {
    use super::SplitIndex;

    /// Places run group by group in each group's own body order, whatever the ids.
    #[test]
    fn split_index_places_bodies_in_the_groups_order() {
        let groups: [&[u32]; 2] = [&[9, 2, 40], &[7, 1]];
        let ix = SplitIndex::of(groups.iter().copied());
        assert_eq!(ix.len(), 5);
        let at: Vec<_> = [9, 2, 40, 7, 1]
            .iter()
            .map(|&id| (ix.group(id), ix.place(id)))
            .collect();
        assert_eq!(
            at,
            vec![
                (Some(0), Some(0)),
                (Some(0), Some(1)),
                (Some(0), Some(2)),
                (Some(1), Some(3)),
                (Some(1), Some(4))
            ]
        );
        assert_eq!((ix.group(3), ix.place(41)), (None, None));
    }
}
