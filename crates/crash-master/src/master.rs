//! The global time loop. Per step: Step{s, dt} to every worker, wait for every report
//! (the barrier), global dt = safety x min stable dt (the core driver's rules, on the
//! reports in body-id order), MEIM update from the reported boxes, migration of bodies
//! whose group changed worker, snapshots at output times.

use crate::assign::assign;
use crate::error::MasterError;
use crate::input::{CostModel, RunInput, RunOptions};
use crate::link::{LinkError, WorkerLink};
use crate::meim::Meim;
use crate::pairs::PairSearch;
use crate::sink::Sink;
use crate::stats::{Migration, RunStats};
use crash_core::contact::{BodyBox, ContactConfig, PairStats};
use crash_core::driver::{check_runaway, choose_dt};
use crash_core::{Body, BodyReport, EnergyLedger, EnergyTotals, Fault, RunConfig, Vec3};
use crash_proto::{Command, Reply, Setup, StepReport};
use std::time::Instant;

mod restart;
pub use restart::MasterCheckpoint;

/// What the master keeps per body (index = position in the sorted id list).
#[derive(Debug, Clone, Copy)]
struct BodyInfo {
    id: u32,
    thickness: f64,
    /// In the MEIM (contact on for the scene and the body).
    meshes: bool,
    /// Extra inflation of the MEIM box over the contact search box.
    extra: f64,
    /// Largest move per step the margin argument allows.
    allowed: f64,
    estimate: f64,
}

/// Relative tolerance of the end-time and output-time comparisons (as the driver).
const TIME_EPS: f64 = 1e-12;

pub(crate) struct Master<'a, L: WorkerLink> {
    links: &'a mut [L],
    opts: RunOptions,
    cfg: RunConfig,
    contact: ContactConfig,
    output_interval: f64,
    info: Vec<BodyInfo>,
    cost: Vec<f64>,
    measured: Vec<Option<f64>>,
    worker_of: Vec<Option<usize>>,
    layout: Vec<Vec<Vec<u32>>>,
    meim: Meim,
    search: PairSearch,
    scene_hash: u64,
    time: f64,
    step: u64,
    /// Length of the last step (the workers' h_prev).
    h_prev: f64,
    next_dt: f64,
    dt0: f64,
    ledger: EnergyLedger,
    reports: Vec<BodyReport>,
    contacts: Vec<PairStats>,
    frames: u64,
    last_frame_step: Option<u64>,
    pub(crate) stats: RunStats,
}

fn ns(t: Instant) -> u64 {
    t.elapsed().as_nanos() as u64
}

impl<'a, L: WorkerLink> Master<'a, L> {
    pub(crate) fn new(
        links: &'a mut [L],
        input: &RunInput,
        opts: RunOptions,
    ) -> Result<Self, MasterError> {
        if links.is_empty() {
            return Err(MasterError::Input("a run needs at least one worker".into()));
        }
        if input.bodies.is_empty() {
            return Err(MasterError::Input("the scene has no bodies".into()));
        }
        if !(opts.margin_factor >= 1.0 && opts.margin_factor.is_finite()) {
            return Err(MasterError::Input(format!(
                "margin factor {} must be finite and >= 1",
                opts.margin_factor
            )));
        }
        let mut ids: Vec<u32> = input.bodies.iter().map(|b| b.id).collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(MasterError::Input(format!(
                "two bodies have the id {}",
                w[0]
            )));
        }
        let mut sorted: Vec<&Body> = input.bodies.iter().collect();
        sorted.sort_by_key(|b| b.id);
        let c = input.contact;
        let info: Vec<BodyInfo> = sorted
            .iter()
            .map(|b| {
                let m = c.margin_for(b);
                let meshes = c.enabled && b.contact;
                BodyInfo {
                    id: b.id,
                    thickness: b.section.thickness,
                    meshes,
                    extra: 0.5 * (opts.margin_factor - 1.0) * m,
                    allowed: 0.5 * (opts.margin_factor - 1.0) * m,
                    estimate: 1.0
                        + if b.kinematic {
                            0.0
                        } else {
                            b.element_count() as f64
                        }
                        + if meshes { b.node_count() as f64 } else { 0.0 },
                }
            })
            .collect();
        let n = info.len();
        // Verlet skin of the level-i search: the MEIM margin of the widest body
        let skin = sorted
            .iter()
            .filter(|b| c.enabled && b.contact)
            .map(|b| opts.margin_factor * c.margin_for(b))
            .fold(0.0, f64::max);
        Ok(Self {
            links,
            opts,
            cfg: input.config,
            contact: c,
            output_interval: input.output_interval,
            cost: info.iter().map(|i| i.estimate).collect(),
            measured: vec![None; n],
            worker_of: vec![None; n],
            layout: Vec::new(),
            meim: Meim::new(&ids, opts.split_after),
            search: PairSearch::new(c.margin, skin),
            info,
            scene_hash: input.scene_hash,
            time: 0.0,
            step: 0,
            h_prev: 0.0,
            next_dt: 0.0,
            dt0: 0.0,
            ledger: EnergyLedger::default(),
            reports: Vec::with_capacity(n),
            contacts: Vec::new(),
            frames: 0,
            last_frame_step: None,
            stats: RunStats::default(),
        })
    }

    fn index(&self, id: u32) -> Option<usize> {
        let i = id as usize;
        if self.info.get(i).is_some_and(|b| b.id == id) {
            return Some(i);
        }
        self.info.binary_search_by_key(&id, |b| b.id).ok()
    }

    fn worker_error(&self, w: usize, e: LinkError) -> MasterError {
        MasterError::Worker {
            step: self.step,
            worker: w,
            peer: self.links[w].peer(),
            reason: e.to_string(),
        }
    }

    /// Send every link its commands, then collect the replies (in order). Errors and
    /// faults end the exchange; of several faults the one of the group with the
    /// smallest body id wins (the same in every placement).
    fn exchange(&mut self, cmds: Vec<Vec<Command>>) -> Result<Vec<Vec<Reply>>, MasterError> {
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
                        return Err(self.worker_error(w, LinkError::Protocol(reason)))
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

    fn bad_reply(&self, w: usize, what: &str) -> MasterError {
        self.worker_error(
            w,
            LinkError::Protocol(format!("unexpected reply to {what}")),
        )
    }

    /// Bodies onto workers, forces of the initial configuration, first dt.
    pub(crate) fn start(
        &mut self,
        bodies: Vec<Body>,
        gravity: Vec3,
        sink: &mut dyn Sink,
    ) -> Result<(), MasterError> {
        let t0 = Instant::now();
        let boxes: Vec<BodyBox> = bodies
            .iter()
            .map(|b| self.inflate(BodyBox::of(b)))
            .collect();
        self.update_meim(&boxes);
        let groups = self.owned_groups();
        let placement = self.place(&groups, true);
        let nw = self.links.len();
        let mut per_worker: Vec<Vec<Body>> = (0..nw).map(|_| Vec::new()).collect();
        for b in bodies {
            let Some(i) = self.index(b.id) else { continue };
            let w = placement[i];
            self.worker_of[i] = Some(w);
            per_worker[w].push(b);
        }
        self.layout = self.layouts(&groups, &placement);
        self.stats.meim_ns_add(ns(t0));
        let setup = Setup {
            gravity,
            contact: self.contact,
        };
        let t1 = Instant::now();
        let cmds = per_worker
            .into_iter()
            .zip(&self.layout)
            .map(|(bs, lay)| {
                vec![
                    Command::Setup(setup),
                    Command::Load(bs),
                    Command::Regroup(lay.clone()),
                    Command::Start,
                ]
            })
            .collect();
        let replies = self.exchange(cmds)?;
        self.stats.stages.migration_ns += ns(t1);
        let mut reports = Vec::with_capacity(nw);
        for (w, mut r) in replies.into_iter().enumerate() {
            match r.pop() {
                Some(Reply::Report(rep)) => reports.push(rep),
                _ => return Err(self.bad_reply(w, "Start")),
            }
        }
        self.gather(reports)?;
        let energy = self
            .ledger
            .update(EnergyTotals::sum(self.reports.iter().map(|r| &r.energy)));
        self.next_dt = self.choose_dt()?;
        self.dt0 = self.next_dt;
        self.stats.dt_min = f64::INFINITY;
        sink.energy(0, 0.0, &energy)
            .map_err(|e| MasterError::Sink(e.to_string()))?;
        sink.contact_stats(0, 0.0, &self.contacts)
            .map_err(|e| MasterError::Sink(e.to_string()))?;
        sink.contacts(0, 0.0, &self.meim.pairs())
            .map_err(|e| MasterError::Sink(e.to_string()))?;
        self.output(sink, true)?;
        Ok(())
    }

    /// Reports of all workers into one list in body-id order.
    fn gather(&mut self, reps: Vec<StepReport>) -> Result<(), MasterError> {
        let n = self.info.len();
        self.reports.clear();
        self.contacts.clear();
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
            return Err(MasterError::Network(format!(
                "step {}: {} of {n} bodies reported",
                self.step, count
            )));
        }
        self.reports.extend(slot.into_iter().flatten());
        self.contacts.sort_by_key(|c| (c.a, c.b));
        Ok(())
    }

    /// Measured group times shared among members by their estimated cost (EMA).
    fn account(&mut self, groups: &[crash_proto::GroupTime]) {
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

    /// The core's rule (`crash_core::driver::choose_dt`), shared by every loop.
    fn choose_dt(&self) -> Result<f64, Fault> {
        choose_dt(&self.cfg, &self.reports, self.dt0, self.step)
    }

    pub(crate) fn finished(&self) -> bool {
        self.time >= self.cfg.end_time * (1.0 - TIME_EPS)
    }

    /// One global step (the last one shortened to land on the end time).
    pub(crate) fn step(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        let _span = tracing::debug_span!("step", step = self.step).entered();
        let mut h = self.next_dt;
        let left = self.cfg.end_time - self.time;
        if left < h && left > 0.0 {
            h = left;
        }
        self.stats.dt_min = self.stats.dt_min.min(h);
        self.stats.dt_max = self.stats.dt_max.max(h);
        let t0 = Instant::now();
        let nw = self.links.len();
        let cmds = (0..nw)
            .map(|_| {
                vec![Command::Step {
                    step: self.step,
                    dt: h,
                }]
            })
            .collect();
        let replies = {
            let _s = tracing::debug_span!("barrier").entered();
            self.exchange(cmds)?
        };
        let wall = ns(t0);
        let mut reps = Vec::with_capacity(nw);
        let mut slowest = 0;
        for (w, mut r) in replies.into_iter().enumerate() {
            match r.pop() {
                Some(Reply::Report(rep)) => {
                    slowest = slowest.max(rep.compute_ns);
                    reps.push(rep);
                }
                _ => return Err(self.bad_reply(w, "Step")),
            }
        }
        let slowest = slowest.min(wall);
        self.stats.stages.compute_ns += slowest;
        self.stats.stages.barrier_ns += wall - slowest;
        self.time += h;
        self.step += 1;
        self.h_prev = h;

        let t1 = Instant::now();
        {
            let _s = tracing::debug_span!("meim").entered();
            self.gather(reps)?;
            let energy = self
                .ledger
                .update(EnergyTotals::sum(self.reports.iter().map(|r| &r.energy)));
            self.runaway(&energy)?;
            self.next_dt = self.choose_dt()?;
            self.check_margin()?;
            sink.energy(self.step, self.time, &energy)
                .map_err(|e| MasterError::Sink(e.to_string()))?;
            sink.contact_stats(self.step, self.time, &self.contacts)
                .map_err(|e| MasterError::Sink(e.to_string()))?;
            let boxes: Vec<BodyBox> = self.reports.iter().map(|r| self.box_of(r)).collect();
            let changed = self.update_meim(&boxes);
            if changed {
                self.stats.group_changes += 1;
                sink.contacts(self.step, self.time, &self.meim.pairs())
                    .map_err(|e| MasterError::Sink(e.to_string()))?;
            }
            let periodic = self.opts.cost == CostModel::Measured
                && self.opts.rebalance_interval > 0
                && self.step.is_multiple_of(self.opts.rebalance_interval);
            self.stats.meim_ns_add(ns(t1));
            if changed || periodic {
                let _s = tracing::debug_span!("migration").entered();
                let t2 = Instant::now();
                self.migrate(changed)?;
                self.stats.stages.migration_ns += ns(t2);
            }
        }
        self.output(sink, false)
    }

    /// The core's runaway guard (`crash_core::driver::check_runaway`).
    fn runaway(&mut self, energy: &EnergyTotals) -> Result<(), Fault> {
        check_runaway(
            &self.cfg,
            &mut self.ledger,
            energy,
            &self.reports,
            self.step,
        )
    }

    /// The margin argument, checked: no contact body may move more in one step than
    /// the MEIM inflation beyond the contact search box allows.
    fn check_margin(&self) -> Result<(), MasterError> {
        for (r, inf) in self.reports.iter().zip(&self.info) {
            if inf.meshes && r.max_move > inf.allowed {
                return Err(MasterError::Margin {
                    step: self.step,
                    body: r.id,
                    moved: r.max_move,
                    allowed: inf.allowed,
                    margin: 2.0 * inf.allowed
                        / (self.opts.margin_factor - 1.0).max(f64::MIN_POSITIVE),
                    factor: self.opts.margin_factor,
                });
            }
        }
        Ok(())
    }

    /// The MEIM box of a body: its contact search box grown by the extra margin.
    fn inflate(&self, mut b: BodyBox) -> BodyBox {
        if let Some(i) = self.index(b.id) {
            let e = Vec3::repeat(self.info[i].extra);
            b.lo -= e;
            b.hi += e;
        }
        b
    }

    fn box_of(&self, r: &BodyReport) -> BodyBox {
        let thickness = self.index(r.id).map_or(0.0, |i| self.info[i].thickness);
        self.inflate(BodyBox {
            id: r.id,
            lo: r.lo,
            hi: r.hi,
            thickness,
        })
    }

    /// Level-i search over the contact bodies (MEIM boxes) and the MEIM update.
    fn update_meim(&mut self, boxes: &[BodyBox]) -> bool {
        let pairs = if self.contact.enabled {
            let meshes: Vec<BodyBox> = boxes
                .iter()
                .filter(|b| self.index(b.id).is_some_and(|i| self.info[i].meshes))
                .copied()
                .collect();
            self.search.pairs(&meshes)
        } else {
            Vec::new()
        };
        let changed = self.meim.update(self.step, &pairs);
        self.stats.max_groups = self.stats.max_groups.max(self.meim.group_count());
        changed
    }

    fn owned_groups(&self) -> Vec<Vec<u32>> {
        self.meim.groups().iter().map(|g| g.to_vec()).collect()
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

    /// Worker per body index for `groups` (ids).
    fn place(&self, groups: &[Vec<u32>], rebalance: bool) -> Vec<usize> {
        let idx: Vec<Vec<usize>> = groups
            .iter()
            .map(|g| g.iter().filter_map(|&id| self.index(id)).collect())
            .collect();
        let to = assign(
            &idx,
            &self.costs(),
            &self.worker_of,
            self.links.len(),
            self.opts.balance_tolerance,
            rebalance,
        );
        let mut out = vec![0; self.info.len()];
        for (g, &w) in idx.iter().zip(&to) {
            for &b in g {
                out[b] = w;
            }
        }
        out
    }

    fn layouts(&self, groups: &[Vec<u32>], placement: &[usize]) -> Vec<Vec<Vec<u32>>> {
        let mut lay: Vec<Vec<Vec<u32>>> = vec![Vec::new(); self.links.len()];
        for g in groups {
            if let Some(i) = g.first().and_then(|&id| self.index(id)) {
                lay[placement[i]].push(g.clone());
            }
        }
        lay
    }

    /// Reassign groups; move bodies whose worker changed (whole state, exact bits);
    /// send the new layouts.
    fn migrate(&mut self, groups_changed: bool) -> Result<(), MasterError> {
        let groups = self.owned_groups();
        let placement = self.place(&groups, true);
        let layout = self.layouts(&groups, &placement);
        if !groups_changed && layout == self.layout {
            return Ok(());
        }
        let nw = self.links.len();
        let mut unload: Vec<Vec<u32>> = vec![Vec::new(); nw];
        let mut moves = Vec::new();
        for (i, &to) in placement.iter().enumerate() {
            if let Some(from) = self.worker_of[i] {
                if from != to {
                    unload[from].push(self.info[i].id);
                    moves.push(Migration {
                        step: self.step,
                        body: self.info[i].id,
                        from,
                        to,
                    });
                }
            }
        }
        let mut load: Vec<Vec<Body>> = (0..nw).map(|_| Vec::new()).collect();
        if !moves.is_empty() {
            let cmds = unload
                .iter()
                .map(|ids| {
                    if ids.is_empty() {
                        Vec::new()
                    } else {
                        vec![Command::Unload(ids.clone())]
                    }
                })
                .collect();
            for (w, r) in self.exchange(cmds)?.into_iter().enumerate() {
                for reply in r {
                    let Reply::Unloaded(bodies) = reply else {
                        return Err(self.bad_reply(w, "Unload"));
                    };
                    for b in bodies {
                        let Some(i) = self.index(b.id) else {
                            return Err(self.bad_reply(w, "Unload"));
                        };
                        load[placement[i]].push(b);
                    }
                }
            }
        }
        let mut cmds: Vec<Vec<Command>> = vec![Vec::new(); nw];
        for (w, bodies) in load.into_iter().enumerate() {
            if !bodies.is_empty() {
                cmds[w].push(Command::Load(bodies));
            }
            if layout[w] != self.layout[w] || !cmds[w].is_empty() || !unload[w].is_empty() {
                cmds[w].push(Command::Regroup(layout[w].clone()));
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
            tracing::debug!("step {}: {} bodies migrated", self.step, moves.len());
        }
        self.stats.migrations.extend(moves);
        self.layout = layout;
        Ok(())
    }

    /// Bodies of every worker, merged into one list in id order.
    pub(crate) fn snapshot(&mut self) -> Result<Vec<Body>, MasterError> {
        let nw = self.links.len();
        let replies = self.exchange((0..nw).map(|_| vec![Command::Snapshot]).collect())?;
        let mut all = Vec::with_capacity(self.info.len());
        for (w, mut r) in replies.into_iter().enumerate() {
            match r.pop() {
                Some(Reply::Snapshot(bodies)) => all.extend(bodies),
                _ => return Err(self.bad_reply(w, "Snapshot")),
            }
        }
        all.sort_by_key(|b| b.id);
        if all.len() != self.info.len() {
            return Err(MasterError::Network(format!(
                "snapshot holds {} of {} bodies",
                all.len(),
                self.info.len()
            )));
        }
        Ok(all)
    }

    /// Frame at the start, whenever an output time is reached, and at the end.
    fn output(&mut self, sink: &mut dyn Sink, force: bool) -> Result<(), MasterError> {
        let due = self.output_interval > 0.0
            && self.time >= (self.frames as f64) * self.output_interval * (1.0 - TIME_EPS);
        if !(force || due) || self.last_frame_step == Some(self.step) {
            return Ok(());
        }
        let t = Instant::now();
        let _s = tracing::debug_span!("output").entered();
        let bodies = self.snapshot()?;
        sink.frame(self.step, self.time, &bodies)
            .map_err(|e| MasterError::Sink(e.to_string()))?;
        self.stats.final_hash = crash_core::hash::state_hash(&bodies);
        self.last_frame_step = Some(self.step);
        while (self.frames as f64) * self.output_interval <= self.time * (1.0 + TIME_EPS)
            && self.output_interval > 0.0
        {
            self.frames += 1;
        }
        self.stats.frames += 1;
        self.stats.stages.output_ns += ns(t);
        Ok(())
    }

    /// Final frame (the state hash) and statistics.
    pub(crate) fn finish(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        self.output(sink, true)?;
        self.stats.steps = self.step;
        self.stats.time = self.time;
        self.stats.workers = self.links.len();
        self.stats.max_energy_error = self.ledger.max_error();
        self.stats.final_groups = self
            .meim
            .groups()
            .iter()
            .map(|g| {
                let w = g
                    .first()
                    .and_then(|&id| self.index(id))
                    .and_then(|i| self.worker_of[i])
                    .unwrap_or(0);
                (g.to_vec(), w)
            })
            .collect();
        Ok(())
    }

    /// Best-effort shutdown of every worker (some may be gone).
    pub(crate) fn shutdown(&mut self, reason: &str) {
        for l in self.links.iter_mut() {
            l.close(reason);
        }
    }
}

impl RunStats {
    fn meim_ns_add(&mut self, t: u64) {
        self.stages.meim_ns += t;
    }
}
