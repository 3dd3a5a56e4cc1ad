//! Placement: the MEIM from the reported boxes, its groups onto workers (balanced,
//! sticky), and migration of the bodies whose group changed worker. A moving body
//! travels as its state; its definition goes along only to a worker that lacks it.

use super::{GroupLayout, Master};
use crate::assign::assign;
use crate::error::MasterError;
use crate::input::CostModel;
use crate::stats::Migration;
use crash_core::contact::BodyBox;
use crash_core::{BodyReport, Vec3};
use crash_link::{BodyLoad, Command, LinkError, Reply, WorkerLink};
use std::collections::BTreeMap;

impl<L: WorkerLink> Master<'_, L> {
    /// The MEIM box of a body: its contact search box grown by the extra margin.
    pub(super) fn inflate(&self, b: BodyBox) -> BodyBox {
        match self.index(b.id) {
            Some(i) => grown(b, self.info[i].extra),
            None => b,
        }
    }

    /// `inflate` of a report's box, with one lookup of its body.
    pub(super) fn box_of(&self, r: &BodyReport) -> BodyBox {
        let b = |thickness| BodyBox {
            id: r.id,
            lo: r.lo,
            hi: r.hi,
            thickness,
        };
        match self.index(r.id) {
            Some(i) => grown(b(self.info[i].thickness), self.info[i].extra),
            None => b(0.0),
        }
    }

    /// Level-i search over the contact bodies (MEIM boxes) and the MEIM update.
    pub(super) fn update_meim(&mut self, boxes: &[BodyBox]) -> bool {
        let pairs = if self.contact.enabled {
            let mut meshes: Vec<BodyBox> = Vec::with_capacity(boxes.len());
            meshes.extend(
                boxes
                    .iter()
                    .filter(|b| self.index(b.id).is_some_and(|i| self.info[i].meshes)),
            );
            self.search.pairs(&meshes)
        } else {
            Vec::new()
        };
        let changed = self.meim.update(self.clock.step, &pairs);
        self.stats.max_groups = self.stats.max_groups.max(self.meim.group_count());
        changed
    }

    /// The MEIM groups with the read-only copies each holds.
    fn owned_groups(&self) -> Vec<GroupLayout> {
        (0..self.meim.group_count())
            .map(|k| (self.meim.group(k).to_vec(), self.meim.copies(k).to_vec()))
            .collect()
    }

    /// Every MEIM group (bodies and read-only copies) lies within one group the
    /// workers hold: a change that only breaks groups up needs no regroup.
    pub(super) fn layout_holds_meim(&self) -> bool {
        let held: Vec<&GroupLayout> = self.layout.iter().flatten().collect();
        let at: BTreeMap<u32, usize> = held
            .iter()
            .enumerate()
            .flat_map(|(k, g)| g.0.iter().map(move |&id| (id, k)))
            .collect();
        (0..self.meim.group_count()).all(|k| {
            let (g, copies) = (self.meim.group(k), self.meim.copies(k));
            let Some(&h) = g.first().and_then(|id| at.get(id)) else {
                return false;
            };
            g.iter().all(|id| at.get(id) == Some(&h))
                && copies.iter().all(|c| held[h].1.contains(c))
        })
    }

    /// Cost per body index under the chosen model.
    fn costs(&self) -> Vec<f64> {
        match self.opts.cost {
            CostModel::Estimated => self.cost.clone(),
            CostModel::Measured => {
                // unmeasured bodies: their estimate at the mean measured ns per unit
                let (mut t, mut e) = (0.0, 0.0);
                for (m, i) in self.measured.iter().zip(&self.info) {
                    if let Some(m) = m {
                        t += m;
                        e += i.estimate;
                    }
                }
                let per = if e > 0.0 { t / e } else { 1.0 };
                self.measured
                    .iter()
                    .zip(&self.info)
                    .map(|(m, i)| m.unwrap_or(i.estimate * per))
                    .collect()
            }
        }
    }

    /// Worker per body index for `groups` (ids; copies cost their owner's worker
    /// nothing and are not counted: measured costs include them in the group's time).
    fn place(&self, groups: &[GroupLayout]) -> Vec<usize> {
        let idx: Vec<Vec<usize>> = groups
            .iter()
            .map(|(g, _)| g.iter().filter_map(|&id| self.index(id)).collect())
            .collect();
        // onto the workers still in the run: assignment sees them as 0..live
        let live: Vec<usize> = (0..self.links.len()).filter(|&w| self.live[w]).collect();
        let slot = |w: usize| live.iter().position(|&l| l == w);
        let current: Vec<Option<usize>> = self.worker_of.iter().map(|w| w.and_then(slot)).collect();
        let to: Vec<usize> = assign(
            &idx,
            &self.costs(),
            &current,
            live.len(),
            self.opts.balance_tolerance,
            true,
        )
        .into_iter()
        .map(|k| live.get(k).copied().unwrap_or(0))
        .collect();
        let mut out = vec![0; self.info.len()];
        for (g, &w) in idx.iter().zip(&to) {
            for &b in g {
                out[b] = w;
            }
        }
        out
    }

    fn layouts(&self, groups: &[GroupLayout], placement: &[usize]) -> Vec<Vec<GroupLayout>> {
        let mut lay: Vec<Vec<GroupLayout>> = vec![Vec::new(); self.links.len()];
        for g in groups {
            if let Some(i) = g.0.first().and_then(|&id| self.index(id)) {
                lay[placement[i]].push(g.clone());
            }
        }
        lay
    }

    /// The Regroup command of one worker's layout.
    fn regroup_cmd(layout: &[GroupLayout]) -> Command {
        Command::Regroup {
            groups: layout.iter().map(|g| g.0.clone()).collect(),
            copies: layout.iter().map(|g| g.1.clone()).collect(),
        }
    }

    /// Per worker: the kinematic bodies its groups copy that it holds in no form after
    /// the bodies are on `placement` (neither the body nor a copy in `before`).
    fn copies_to_send(
        &self,
        layout: &[Vec<GroupLayout>],
        before: &[Vec<GroupLayout>],
        placement: &[usize],
    ) -> Vec<Vec<u32>> {
        layout
            .iter()
            .enumerate()
            .map(|(w, groups)| {
                let mut need: Vec<u32> = groups.iter().flat_map(|g| g.1.iter().copied()).collect();
                need.sort_unstable();
                need.dedup();
                need.retain(|&id| {
                    let owned_here = self.index(id).is_some_and(|i| placement[i] == w);
                    let copied_here = before
                        .get(w)
                        .is_some_and(|gs| gs.iter().any(|g| g.1.contains(&id)));
                    !owned_here && !copied_here
                });
                need
            })
            .collect()
    }

    /// Place the current MEIM groups on workers from scratch (start, resume): the
    /// worker of each body (by index).
    pub(super) fn place_all(&mut self) -> Vec<usize> {
        let groups = self.owned_groups();
        let placement = self.place(&groups);
        for (i, &w) in placement.iter().enumerate() {
            self.worker_of[i] = Some(w);
        }
        self.layout = self.layouts(&groups, &placement);
        placement
    }

    /// Hand the bodies to their workers one at a time (each built or taken, sent, and
    /// dropped before the next: the master never holds the model), then set every
    /// worker's groups. `body(id)` gives the body to load. The commands go out one
    /// after the other and the acks are read at the end: a worker decodes one body
    /// while the master builds and encodes the next. The bodies of a split planned at
    /// the start go to each of its holders (`plan_at_start`).
    pub(super) fn load_all(
        &mut self,
        placement: &[usize],
        mut body: impl FnMut(u32) -> Result<BodyLoad, MasterError>,
    ) -> Result<(), MasterError> {
        let nw = self.links.len();
        let mut sent = Pipeline::new(nw);
        let setup = self.setup();
        for w in 0..nw {
            sent.send(self, w, Command::Setup(setup.clone()));
        }
        let at = self.clock;
        let copies = self.copies_to_send(&self.layout, &[], placement);
        let mut built = Ok(());
        let planned = self.planned_by_id();
        let ids: Vec<u32> = self.info.iter().map(|i| i.id).collect();
        for (&id, &to) in ids.iter().zip(placement) {
            let load = match body(id) {
                Ok(l) => l,
                Err(e) => {
                    // the replies of what went out are still read: none is left on a link
                    built = Err(e);
                    break;
                }
            };
            // read-only copies for the other workers' groups that touch it
            for (w, need) in copies.iter().enumerate() {
                if need.contains(&id) {
                    let bodies = vec![load.clone()];
                    sent.send(self, w, Command::LoadCopies { at, bodies });
                }
            }
            if let Some(&k) = planned.get(&id) {
                for w in self.keep_planned(k, &load) {
                    let bodies = vec![load.clone()];
                    sent.send(self, w, Command::Load { at, bodies });
                }
            }
            let bodies = vec![load];
            sent.send(self, to, Command::Load { at, bodies });
        }
        if built.is_ok() {
            let regroups: Vec<Command> = self
                .layout
                .iter()
                .enumerate()
                .map(|(w, l)| {
                    let mut l = l.clone();
                    l.extend(self.shadows_of(w).map(|g| (g.to_vec(), Vec::new())));
                    Self::regroup_cmd(&l)
                })
                .collect();
            for (w, cmd) in regroups.into_iter().enumerate() {
                sent.send(self, w, cmd);
            }
        }
        let Pipeline { counts, failed } = sent;
        let replies = self.settle(&counts, failed, |m, w| m.links[w].recv())?;
        built?;
        for (w, r) in replies.into_iter().enumerate() {
            if r.iter().any(|x| !matches!(x, Reply::Ack)) {
                return Err(self.bad_reply(w, "Setup, Load or Regroup"));
            }
        }
        Ok(())
    }

    /// An exchange whose every reply must be Ack.
    pub(super) fn expect_acks(
        &mut self,
        cmds: Vec<Vec<Command>>,
        what: &str,
    ) -> Result<(), MasterError> {
        for (w, r) in self.exchange(cmds)?.into_iter().enumerate() {
            if r.iter().any(|x| !matches!(x, Reply::Ack)) {
                return Err(self.bad_reply(w, what));
            }
        }
        Ok(())
    }

    /// Reassign groups; move bodies whose worker changed (state, exact bits; the
    /// definition only to a worker that lacks it); send the new layouts.
    pub(super) fn migrate(&mut self, groups_changed: bool) -> Result<(), MasterError> {
        let groups = self.owned_groups();
        let placement = self.place(&groups);
        let layout = self.layouts(&groups, &placement);
        if !groups_changed && layout == self.layout {
            return Ok(());
        }
        let nw = self.links.len();
        let mut unload: Vec<Vec<u32>> = vec![Vec::new(); nw];
        let mut with_def: Vec<Vec<u32>> = vec![Vec::new(); nw];
        let mut moves = Vec::new();
        for (i, &to) in placement.iter().enumerate() {
            if let Some(from) = self.worker_of[i] {
                if from != to {
                    let id = self.info[i].id;
                    unload[from].push(id);
                    if !self.links[to].has_definition(id) {
                        with_def[from].push(id);
                    }
                    moves.push(Migration {
                        step: self.clock.step,
                        body: id,
                        from,
                        to,
                    });
                }
            }
        }
        // kinematic bodies lent (their state copied, before any unload) to workers whose
        // new groups touch them and that hold them in no form: (lender, id, borrower)
        let mut lends: Vec<(usize, u32, usize)> = Vec::new();
        for (w, need) in self
            .copies_to_send(&layout, &self.layout, &placement)
            .into_iter()
            .enumerate()
        {
            for id in need {
                if let Some(from) = self.index(id).and_then(|i| self.worker_of[i]) {
                    lends.push((from, id, w));
                }
            }
        }
        let mut load: Vec<Vec<BodyLoad>> = (0..nw).map(|_| Vec::new()).collect();
        let mut lent: Vec<Vec<BodyLoad>> = (0..nw).map(|_| Vec::new()).collect();
        if !moves.is_empty() || !lends.is_empty() {
            let mut cmds: Vec<Vec<Command>> = vec![Vec::new(); nw];
            // one body per message: each reply stays under MAX_MESSAGE
            for &(from, id, to) in &lends {
                let with_def = if self.links[to].has_definition(id) {
                    Vec::new()
                } else {
                    vec![id]
                };
                cmds[from].push(Command::Lend {
                    ids: vec![id],
                    with_def,
                });
            }
            for (w, (ids, with_def)) in unload.iter().zip(&with_def).enumerate() {
                for &id in ids {
                    cmds[w].push(Command::Unload {
                        ids: vec![id],
                        with_def: if with_def.contains(&id) {
                            vec![id]
                        } else {
                            Vec::new()
                        },
                    });
                }
            }
            let mut lend_of: Vec<std::collections::VecDeque<usize>> =
                (0..nw).map(|_| Default::default()).collect();
            for &(from, _, to) in &lends {
                lend_of[from].push_back(to);
            }
            for (w, r) in self.exchange(cmds)?.into_iter().enumerate() {
                for reply in r {
                    let Reply::Unloaded(bodies) = reply else {
                        return Err(self.bad_reply(w, "Unload"));
                    };
                    // the lends were sent first: their replies come first
                    if let Some(to) = lend_of[w].pop_front() {
                        lent[to].extend(bodies);
                        continue;
                    }
                    for b in bodies {
                        let Some(i) = self.index(b.id) else {
                            return Err(self.bad_reply(w, "Unload"));
                        };
                        load[placement[i]].push(b);
                    }
                }
            }
        }
        let at = self.clock;
        let mut cmds: Vec<Vec<Command>> = vec![Vec::new(); nw];
        for (w, (bodies, copies)) in load.into_iter().zip(lent).enumerate() {
            for b in bodies {
                cmds[w].push(Command::Load {
                    at,
                    bodies: vec![b],
                });
            }
            for b in copies {
                cmds[w].push(Command::LoadCopies {
                    at,
                    bodies: vec![b],
                });
            }
            if layout[w] != self.layout[w] || !cmds[w].is_empty() || !unload[w].is_empty() {
                cmds[w].push(Self::regroup_cmd(&layout[w]));
            }
        }
        for (w, r) in self.exchange(cmds)?.into_iter().enumerate() {
            if r.iter().any(|x| !matches!(x, Reply::Ack)) {
                return Err(self.bad_reply(w, "Load/Regroup"));
            }
        }
        for (i, &w) in placement.iter().enumerate() {
            self.worker_of[i] = Some(w);
        }
        if !moves.is_empty() {
            tracing::debug!("step {}: {} bodies migrated", self.clock.step, moves.len());
        }
        self.stats.migrations.extend(moves);
        self.log_group_changes(&self.layout, &layout);
        self.layout = layout;
        Ok(())
    }
}

/// `b` grown by `extra` on every side.
fn grown(mut b: BodyBox, extra: f64) -> BodyBox {
    let e = Vec3::repeat(extra);
    b.lo -= e;
    b.hi += e;
    b
}

/// Commands sent without waiting for their replies (counted per worker; a worker's
/// first failed send ends its sending), read by `settle` at the end.
struct Pipeline {
    counts: Vec<usize>,
    failed: Vec<Option<LinkError>>,
}

impl Pipeline {
    fn new(nw: usize) -> Self {
        Self {
            counts: vec![0; nw],
            failed: vec![None; nw],
        }
    }

    /// Send `cmd` to worker `w` unless it is dropped or a send to it failed.
    fn send<L: WorkerLink>(&mut self, m: &mut Master<'_, L>, w: usize, cmd: Command) {
        if !m.live[w] || self.failed[w].is_some() {
            return;
        }
        match m.links[w].send(cmd) {
            Ok(()) => self.counts[w] += 1,
            Err(e) => self.failed[w] = Some(e),
        }
    }
}
