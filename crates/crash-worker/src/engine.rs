//! The worker's compute engine: the bodies it holds, organised in one
//! `crash_core::Group` per MEIM group (connected component), advanced in parallel.
//!
//! Why one core Group per MEIM group rather than one for all the worker's bodies: a
//! group then computes exactly the same bits whatever else its worker holds (the
//! partition is the master's MEIM grouping, identical in every mode), and rayon runs
//! groups side by side (a body of fewer than 256 elements is a single chunk of the core's
//! element loop, so small bodies only parallelise across groups).
//!
//! The engine is plain synchronous code: local mode calls `handle` directly, the
//! worker process calls it on its compute pool, off the communication runtime.
//!
//! Kinematic bodies (every degree of freedom prescribed) never join groups: a group
//! that touches one holds a read-only copy of it, advanced by the same prescribed law
//! (so bit-identical to the owner), in contact with the group's bodies, never reported.
//! Copies are made from the owner or another copy on this worker, or arrive by
//! LoadCopies; between a Regroup's dissolving and rebuilding they wait in `spare`.
//!
//! Time: the engine keeps no clock of its own. Every Step and Load carries the run's
//! clock; the engine only remembers the clock its bodies are at, to refuse a command
//! meant for another moment (so a resumed run continues on any set of workers).

mod split;
mod step;

use crate::error::EngineError;
use crash_core::contact::PairStats;
use crash_core::{Body, BodyDef, BodyReport, BodyState, Clock, Fault, Group};
use crash_io::FrameBody;
use crash_link::{BodyLoad, Command, GroupTime, Reply, Setup, StepReport};
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::time::Instant;

/// Bodies of one worker, grouped, and the definitions it has received.
#[derive(Debug, Default)]
pub struct Engine {
    setup: Option<Setup>,
    /// Sorted by smallest body id; bodies inside each group sorted by id.
    groups: Vec<Group>,
    /// Loaded (or left over after an unload) but not yet placed by a Regroup.
    loose: Vec<Body>,
    /// Read-only copies of kinematic bodies not in a group (loaded by LoadCopies or
    /// left over from dissolved groups), by id; the next Regroup uses or drops them.
    spare: BTreeMap<u32, Body>,
    /// Every definition received, kept after a body leaves (it may come back: then only
    /// its state travels).
    defs: BTreeMap<u32, Arc<BodyDef>>,
    /// The clock the held bodies are at (None: no bodies yet).
    at: Option<Clock>,
    /// A fault left the groups at different steps: only Frame, States and Shutdown
    /// remain.
    broken: bool,
    /// Groups split over workers that this worker holds parts of (`split.rs`).
    shared: Vec<split::Shared>,
    /// The step in flight for the split groups: its clock, length and what is due
    /// (set by Step, read by Halo).
    pending: Option<(Clock, f64, crash_core::Due)>,
    /// This worker's side of the direct halo exchange with the other holders of its
    /// split groups (a worker process; None in process: the master relays).
    peers: Option<crash_link::peer::Peers>,
    /// A group split here, its parts built after the reply (`settle`), and why their
    /// build failed if it did (every command but Reset and Shutdown is refused then).
    unbuilt: Option<split::Unbuilt>,
    unbuildable: Option<String>,
}

impl Engine {
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether the definition of body `id` is held.
    pub fn has_definition(&self, id: u32) -> bool {
        self.defs.contains_key(&id)
    }

    /// The clock the held bodies are at.
    pub fn clock(&self) -> Option<Clock> {
        self.at
    }

    /// Number of bodies held (copies not counted).
    pub fn body_count(&self) -> usize {
        self.loose.len()
            + self.groups.iter().map(|g| g.owned().count()).sum::<usize>()
            + self.split_home_ids().count()
    }

    /// Current group layout (owned body ids).
    pub fn layout(&self) -> Vec<Vec<u32>> {
        self.groups
            .iter()
            .map(|g| g.owned().map(|b| b.def.id).collect())
            .collect()
    }

    /// The read-only copies each group holds (ids), in group order.
    pub fn copies(&self) -> Vec<Vec<u32>> {
        self.groups.iter().map(|g| g.copies.clone()).collect()
    }

    /// Every instance (owned body or copy) of body `id` held, for checks: copies must
    /// stay bit-identical to their owner.
    pub fn instances(&self, id: u32) -> Vec<&Body> {
        self.groups
            .iter()
            .flat_map(|g| g.bodies.iter())
            .chain(&self.loose)
            .chain(self.spare.values())
            .filter(|b| b.def.id == id)
            .collect()
    }

    /// Carry out one command.
    pub fn handle(&mut self, cmd: Command) -> Reply {
        self.settle();
        if let Some(why) = &self.unbuildable {
            if !matches!(cmd, Command::Reset | Command::Shutdown(_)) {
                return Reply::Error(why.clone());
            }
        }
        let res = match cmd {
            Command::Setup(s) => {
                for g in &mut self.groups {
                    g.gravity = s.gravity;
                    g.contact = s.contact;
                    g.reactions = s.reactions;
                    g.probes = s.probes.to_vec();
                }
                self.setup = Some(s);
                Ok(Reply::Ack)
            }
            Command::Load { at, bodies } => self.load(at, bodies),
            Command::LoadCopies { at, bodies } => self.load_copies(at, bodies),
            Command::Unload { ids, with_def } => self.unload(&ids, &with_def),
            Command::Lend { ids, with_def } => self.lend(&ids, &with_def),
            Command::Regroup { groups, copies } => self.regroup(groups, copies),
            Command::Start => {
                if let Err(e) = self.check_clock(&Clock::default()) {
                    return Reply::Error(e.to_string());
                }
                if !self.shared.is_empty() {
                    return Reply::Error(EngineError::Split("Start").to_string());
                }
                self.at = Some(Clock::default());
                return self.run(|g| g.start(), true);
            }
            Command::Step {
                at,
                dt,
                kin_nodes,
                due,
                contact,
                direct,
            } => {
                return self.step(&at, dt, kin_nodes, due, &contact, direct);
            }
            Command::Frame(ids) => self.frame(&ids).map(Reply::Frame),
            Command::States(ids) if ids.is_empty() => self
                .check_assembled()
                .map(|()| Reply::States(self.states())),
            Command::States(ids) => self.states_of(&ids).map(Reply::States),
            Command::Reset => {
                // a rollback: the checkpoint's states follow in Loads (definitions kept)
                self.groups.clear();
                self.loose.clear();
                self.shared.clear();
                self.pending = None;
                self.at = None;
                self.broken = false;
                self.unbuilt = None;
                self.unbuildable = None;
                Ok(Reply::Ack)
            }
            Command::Shutdown(_) => Ok(Reply::Ack),
            Command::Split(spec) => self.split(spec),
            Command::Share { at, spec, bodies } => self.share(at, spec, bodies),
            Command::Halo(parts) => return self.halo(parts),
            Command::Contact(dts) => return self.contact(dts),
            Command::Parts => Ok(self.parts()),
            Command::Assemble(parts) => self.assemble(parts),
            Command::Unsplit => self.unsplit(),
            Command::PartFrames(ids) => self.part_frames(&ids).map(Reply::PartFrames),
        };
        res.unwrap_or_else(|e| Reply::Error(e.to_string()))
    }

    /// A command for clock `at` fits the held bodies (any clock fits an empty engine).
    fn check_clock(&self, at: &Clock) -> Result<(), EngineError> {
        match self.at {
            Some(c) if self.body_count() > 0 && !c.same_as(at) => Err(EngineError::Clock {
                asked_step: at.step,
                asked_time: at.time,
                held_step: c.step,
                held_time: c.time,
            }),
            _ => Ok(()),
        }
    }

    fn new_group(&self, bodies: Vec<Body>, copies: Vec<Body>) -> Result<Group, EngineError> {
        let setup = self.setup.as_ref().ok_or(EngineError::NoSetup)?;
        let mut g = Group::with_copies(bodies, copies, setup.gravity);
        g.contact = setup.contact;
        g.reactions = setup.reactions;
        if !setup.probes.is_empty() {
            // only this group's bodies: the lookup per step stays short
            let mut ids: Vec<u32> = g.bodies.iter().map(|b| b.def.id).collect();
            ids.sort_unstable();
            g.probes = setup
                .probes
                .iter()
                .filter(|p| ids.binary_search(&p.0).is_ok())
                .copied()
                .collect();
        }
        Ok(g)
    }

    /// Ids of the owned bodies (copies not included).
    fn ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.groups
            .iter()
            .flat_map(|g| g.owned())
            .chain(&self.loose)
            .map(|b| b.def.id)
            .chain(self.split_home_ids())
    }

    fn load_copies(&mut self, at: Clock, bodies: Vec<BodyLoad>) -> Result<Reply, EngineError> {
        self.check_clock(&at)?;
        for b in bodies {
            let known = self.defs.get(&b.id).cloned();
            let body = b.into_body(known.as_ref())?;
            if !body.def.kinematic {
                return Err(EngineError::NotKinematic(body.def.id));
            }
            self.defs.insert(body.def.id, body.def.clone());
            self.spare.insert(body.def.id, body);
        }
        self.at = Some(at);
        Ok(Reply::Ack)
    }

    /// The state of owned kinematic bodies, kept here, for another worker's copies.
    fn lend(&mut self, ids: &[u32], with_def: &[u32]) -> Result<Reply, EngineError> {
        let held: BTreeMap<u32, &Body> = self.held().into_iter().map(|b| (b.def.id, b)).collect();
        let mut out = Vec::with_capacity(ids.len());
        for id in ids {
            let b = held.get(id).ok_or(EngineError::NotHeld {
                id: *id,
                what: "a copy",
            })?;
            if !b.def.kinematic {
                return Err(EngineError::NotKinematic(*id));
            }
            out.push(BodyLoad {
                id: *id,
                def: with_def.contains(id).then(|| b.def.clone()),
                state: b.settled_state(),
            });
        }
        Ok(Reply::Unloaded(out))
    }

    fn load(&mut self, at: Clock, bodies: Vec<BodyLoad>) -> Result<Reply, EngineError> {
        self.check_clock(&at)?;
        let held: BTreeSet<u32> = self.ids().collect();
        let mut built = Vec::with_capacity(bodies.len());
        for b in bodies {
            if held.contains(&b.id) {
                return Err(EngineError::AlreadyHeld(b.id));
            }
            let known = self.defs.get(&b.id).cloned();
            let body = b.into_body(known.as_ref())?;
            built.push(body);
        }
        for b in &built {
            self.defs.insert(b.def.id, b.def.clone());
        }
        self.loose.extend(built);
        self.at = Some(at);
        Ok(Reply::Ack)
    }

    /// Split a dissolved group: owned bodies to `owned`, copies to `spare`.
    fn dissolve(spare: &mut BTreeMap<u32, Body>, g: Group, mut owned: impl FnMut(Body)) {
        for b in g.bodies {
            if g.copies.binary_search(&b.def.id).is_ok() {
                spare.entry(b.def.id).or_insert(b);
            } else {
                owned(b);
            }
        }
    }

    /// Take every body out of the groups into an id-ordered map (copies to `spare`).
    fn pool(&mut self) -> BTreeMap<u32, Body> {
        let mut all = BTreeMap::new();
        for g in std::mem::take(&mut self.groups) {
            Self::dissolve(&mut self.spare, g, |b| {
                all.insert(b.def.id, b);
            });
        }
        for b in self.loose.drain(..) {
            all.insert(b.def.id, b);
        }
        all
    }

    fn unload(&mut self, ids: &[u32], with_def: &[u32]) -> Result<Reply, EngineError> {
        if !self.shared.is_empty() {
            return Err(EngineError::Split("Unload"));
        }
        let held: BTreeSet<u32> = self.ids().collect();
        if let Some(id) = ids.iter().find(|id| !held.contains(id)) {
            return Err(EngineError::NotHeld {
                id: *id,
                what: "an unload",
            });
        }
        // Groups losing members are dissolved; the master sends the new layout next.
        let mut out = Vec::with_capacity(ids.len());
        let take: BTreeSet<u32> = ids.iter().copied().collect();
        let mut kept = Vec::new();
        for g in std::mem::take(&mut self.groups) {
            if g.owned().any(|b| take.contains(&b.def.id)) {
                let (loose, spare) = (&mut self.loose, &mut self.spare);
                Self::dissolve(spare, g, |b| {
                    if take.contains(&b.def.id) {
                        out.push(b);
                    } else {
                        loose.push(b);
                    }
                });
            } else {
                kept.push(g);
            }
        }
        self.groups = kept;
        let (gone, stay): (Vec<Body>, Vec<Body>) =
            self.loose.drain(..).partition(|b| take.contains(&b.def.id));
        self.loose = stay;
        out.extend(gone);
        out.sort_by_key(|b| b.def.id);
        let with_def: BTreeSet<u32> = with_def.iter().copied().collect();
        Ok(Reply::Unloaded(
            out.into_iter()
                .map(|mut b| {
                    // forces carried as node sums leave in the slots (crash_core::summed)
                    b.settle();
                    BodyLoad {
                        id: b.def.id,
                        def: with_def.contains(&b.def.id).then_some(b.def),
                        state: b.state,
                    }
                })
                .collect(),
        ))
    }

    fn regroup(
        &mut self,
        layout: Vec<Vec<u32>>,
        copies: Vec<Vec<u32>>,
    ) -> Result<Reply, EngineError> {
        if !self.shared.is_empty() {
            return Err(EngineError::Split("Regroup"));
        }
        let mut listed = BTreeSet::new();
        for id in layout.iter().flatten() {
            if !listed.insert(*id) {
                return Err(EngineError::Twice(*id));
            }
        }
        let held: BTreeSet<u32> = self.ids().collect();
        if listed != held {
            let missing: Vec<u32> = listed.difference(&held).copied().collect();
            let extra: Vec<u32> = held.difference(&listed).copied().collect();
            return Err(EngineError::Layout { missing, extra });
        }
        // (members, copies) of each group, sorted; groups by smallest member
        let mut wanted: Vec<(Vec<u32>, Vec<u32>)> = layout
            .into_iter()
            .enumerate()
            .map(|(k, mut g)| {
                g.sort_unstable();
                let mut c = copies.get(k).cloned().unwrap_or_default();
                c.sort_unstable();
                c.dedup();
                c.retain(|id| g.binary_search(id).is_err());
                (g, c)
            })
            .filter(|(g, _)| !g.is_empty())
            .collect();
        wanted.sort_by_key(|(g, _)| g.first().copied());
        // Groups whose membership (copies included) is unchanged are kept as they are
        // (with their contact search caches); the others are rebuilt from their bodies.
        let keys: BTreeSet<(&[u32], &[u32])> = wanted
            .iter()
            .map(|(g, c)| (g.as_slice(), c.as_slice()))
            .collect();
        let mut keep: BTreeMap<(Vec<u32>, Vec<u32>), Group> = BTreeMap::new();
        let mut rest = Vec::new();
        for g in self.groups.drain(..) {
            let ids: Vec<u32> = g.owned().map(|b| b.def.id).collect();
            if keys.contains(&(ids.as_slice(), g.copies.as_slice())) {
                keep.insert((ids, g.copies.clone()), g);
            } else {
                rest.push(g);
            }
        }
        self.groups = rest;
        let mut pool = self.pool();
        // a copy is made from any instance held: all are at the same clock, with the
        // same motion bits (contact forces and energy records are the copy's own)
        let source = |id: u32,
                      pool: &BTreeMap<u32, Body>,
                      spare: &BTreeMap<u32, Body>,
                      keep: &BTreeMap<(Vec<u32>, Vec<u32>), Group>|
         -> Result<Body, EngineError> {
            let b = pool
                .get(&id)
                .or_else(|| spare.get(&id))
                .or_else(|| {
                    keep.values()
                        .flat_map(|g| g.bodies.iter())
                        .find(|b| b.def.id == id)
                })
                .ok_or(EngineError::NoCopySource(id))?;
            if !b.def.kinematic {
                return Err(EngineError::NotKinematic(id));
            }
            Ok(read_only_copy(b))
        };
        let mut made: Vec<Vec<Body>> = Vec::with_capacity(wanted.len());
        for (g, c) in &wanted {
            if keep.contains_key(&(g.clone(), c.clone())) {
                made.push(Vec::new());
                continue;
            }
            let copies = c
                .iter()
                .map(|&id| source(id, &pool, &self.spare, &keep))
                .collect::<Result<Vec<Body>, _>>()?;
            made.push(copies);
        }
        let mut groups = Vec::with_capacity(wanted.len());
        for ((ids, c), copies) in wanted.into_iter().zip(made) {
            if let Some(g) = keep.remove(&(ids.clone(), c)) {
                groups.push(g);
                continue;
            }
            let bodies = ids.iter().filter_map(|id| pool.remove(id)).collect();
            groups.push(self.new_group(bodies, copies)?);
        }
        self.groups = groups;
        // copies no group asked for are dropped
        self.spare.clear();
        Ok(Reply::Ack)
    }

    /// Run `f` on every group in parallel; reports in group order, the fault of the
    /// first faulting group (smallest body id) if any.
    fn run(
        &mut self,
        f: impl Fn(&mut Group) -> Result<Vec<BodyReport>, Fault> + Sync + Send,
        kin_nodes: bool,
    ) -> Reply {
        if self.broken {
            return Reply::Error(EngineError::Broken.to_string());
        }
        if !self.loose.is_empty() {
            return Reply::Error(EngineError::Unplaced(self.loose.len()).to_string());
        }
        let t0 = Instant::now();
        let results: Vec<(Result<Vec<BodyReport>, Fault>, u64)> = self
            .groups
            .par_iter_mut()
            .map(|g| {
                let t = Instant::now();
                let r = f(g);
                (r, t.elapsed().as_nanos() as u64)
            })
            .collect();
        let mut rep = StepReport {
            bodies: Vec::with_capacity(self.body_count()),
            groups: Vec::with_capacity(results.len()),
            compute_ns: 0,
            contacts: Vec::new(),
            codec_ns: 0,
            probes: Vec::new(),
            parts: Vec::new(),
            part_dts: Default::default(),
            split_contacts: Vec::new(),
            split_limits: Vec::new(),
            halo: None,
        };
        for (g, (r, nanos)) in self.groups.iter().zip(results) {
            let first = g.first();
            match r {
                Ok(reports) => {
                    rep.bodies.extend(reports);
                    rep.contacts
                        .extend(g.contact_stats().iter().map(|s| s.for_report(kin_nodes)));
                    rep.probes.extend_from_slice(g.probed());
                }
                Err(fault) => {
                    self.broken = true;
                    // no split group's pass is run here (Step: `handle`)
                    return Reply::Fault {
                        group_first: first,
                        fault,
                        split_contacts: Some(Vec::new()),
                    };
                }
            }
            rep.groups.push(GroupTime { first, nanos });
        }
        rep.compute_ns = t0.elapsed().as_nanos() as u64;
        Reply::Report(rep)
    }

    /// Every body held, sorted by id.
    pub fn bodies(&self) -> Vec<&Body> {
        self.held()
    }

    /// Contact statistics of the last force pass, group after group.
    pub fn contact_stats(&self) -> Vec<PairStats> {
        self.groups
            .iter()
            .flat_map(|g| g.contact_stats().iter().cloned())
            .collect()
    }

    /// The owned bodies (not copies).
    fn held(&self) -> Vec<&Body> {
        let mut out: Vec<&Body> = self
            .groups
            .iter()
            .flat_map(|g| g.owned())
            .chain(&self.loose)
            .chain(self.split_home_bodies())
            .collect();
        out.sort_by_key(|b| b.def.id);
        out
    }

    /// What an output frame shows of the bodies `ids` (all held), in that order.
    pub fn frame(&self, ids: &[u32]) -> Result<Vec<FrameBody>, EngineError> {
        self.check_assembled_of(Some(ids))?;
        let held: BTreeMap<u32, &Body> = self.held().into_iter().map(|b| (b.def.id, b)).collect();
        ids.iter()
            .map(|id| {
                held.get(id)
                    .map(|b| FrameBody::capture_deferred(b))
                    .ok_or(EngineError::NotHeld {
                        id: *id,
                        what: "a frame",
                    })
            })
            .collect()
    }

    /// The state of these bodies, in the order asked.
    pub fn states_of(&self, ids: &[u32]) -> Result<Vec<(u32, BodyState)>, EngineError> {
        self.check_assembled()?;
        let held: BTreeMap<u32, &Body> = self.held().into_iter().map(|b| (b.def.id, b)).collect();
        ids.iter()
            .map(|id| {
                held.get(id)
                    .map(|b| (*id, b.settled_state()))
                    .ok_or(EngineError::NotHeld {
                        id: *id,
                        what: "the state",
                    })
            })
            .collect()
    }

    /// The state of every body held, sorted by id.
    pub fn states(&self) -> Vec<(u32, BodyState)> {
        self.held()
            .into_iter()
            .map(|b| (b.def.id, b.settled_state()))
            .collect()
    }
}

/// A read-only copy of a kinematic body: its definition and motion, no contact forces of
/// its own yet, a blank energy record (a copy's energy is never reported).
fn read_only_copy(b: &Body) -> Body {
    let mut copy = b.clone();
    for f in &mut copy.state.f_contact {
        *f = crash_core::Vec3::zeros();
    }
    copy.state.energy = Default::default();
    copy
}
