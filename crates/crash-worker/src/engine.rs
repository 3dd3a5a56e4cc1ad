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

use crash_core::{Body, BodyReport, Fault, Group};
use crash_proto::{Command, GroupTime, Reply, Setup, StepReport};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::time::Instant;

/// Bodies of one worker and the shared clock of its groups.
#[derive(Debug, Default)]
pub struct Engine {
    setup: Option<Setup>,
    /// Sorted by smallest body id; bodies inside each group sorted by id.
    groups: Vec<Group>,
    /// Loaded (or left over after an unload) but not yet placed by a Regroup.
    loose: Vec<Body>,
    time: f64,
    step: u64,
    h_prev: f64,
    /// A fault left the groups at different steps: only Snapshot and Shutdown remain.
    broken: bool,
}

impl Engine {
    pub fn new() -> Self {
        Self::default()
    }

    /// Set the clock of an empty engine (a restart: the groups built from the bodies
    /// loaded next continue at this time, step and last step length).
    pub fn set_clock(&mut self, time: f64, step: u64, h_prev: f64) -> Result<(), String> {
        if self.body_count() > 0 {
            return Err("the clock can only be set before bodies are loaded".into());
        }
        self.time = time;
        self.step = step;
        self.h_prev = h_prev;
        Ok(())
    }

    /// Number of bodies held.
    pub fn body_count(&self) -> usize {
        self.loose.len() + self.groups.iter().map(|g| g.bodies.len()).sum::<usize>()
    }

    /// Current group layout (body ids).
    pub fn layout(&self) -> Vec<Vec<u32>> {
        self.groups
            .iter()
            .map(|g| g.bodies.iter().map(|b| b.id).collect())
            .collect()
    }

    /// Carry out one command.
    pub fn handle(&mut self, cmd: Command) -> Reply {
        let res = match cmd {
            Command::Setup(s) => {
                for g in &mut self.groups {
                    g.gravity = s.gravity;
                    g.contact = s.contact;
                }
                self.setup = Some(s);
                Ok(Reply::Ack)
            }
            Command::Load(bodies) => self.load(bodies),
            Command::Unload(ids) => self.unload(&ids),
            Command::Regroup(layout) => self.regroup(layout),
            Command::Start => return self.run(|g| g.start()),
            Command::Step { step, dt } => {
                if self.step != step {
                    Err(format!(
                        "asked for step {step}, but this worker's groups are at step {}",
                        self.step
                    ))
                } else if !(dt.is_finite() && dt > 0.0) {
                    Err(format!("step {step}: invalid time step {dt}"))
                } else {
                    let reply = self.run(|g| g.advance(dt));
                    self.time += dt;
                    self.step += 1;
                    self.h_prev = dt;
                    return reply;
                }
            }
            Command::Snapshot => Ok(Reply::Snapshot(self.snapshot())),
            Command::Shutdown(_) => Ok(Reply::Ack),
        };
        res.unwrap_or_else(Reply::Error)
    }

    fn new_group(&self, bodies: Vec<Body>) -> Result<Group, String> {
        let setup = self
            .setup
            .ok_or("bodies arrived before the run setup (gravity, contact)")?;
        let mut g = Group::new(bodies, setup.gravity);
        g.contact = setup.contact;
        g.time = self.time;
        g.step = self.step;
        g.h_prev = self.h_prev;
        Ok(g)
    }

    fn ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.groups
            .iter()
            .flat_map(|g| g.bodies.iter())
            .chain(&self.loose)
            .map(|b| b.id)
    }

    fn load(&mut self, bodies: Vec<Body>) -> Result<Reply, String> {
        let held: std::collections::BTreeSet<u32> = self.ids().collect();
        for b in &bodies {
            if held.contains(&b.id) {
                return Err(format!("body {} is already on this worker", b.id));
            }
        }
        self.loose.extend(bodies);
        Ok(Reply::Ack)
    }

    /// Take every body out of the groups into an id-ordered map.
    fn pool(&mut self) -> BTreeMap<u32, Body> {
        let mut all = BTreeMap::new();
        for g in self.groups.drain(..) {
            for b in g.bodies {
                all.insert(b.id, b);
            }
        }
        for b in self.loose.drain(..) {
            all.insert(b.id, b);
        }
        all
    }

    fn unload(&mut self, ids: &[u32]) -> Result<Reply, String> {
        let held: std::collections::BTreeSet<u32> = self.ids().collect();
        if let Some(id) = ids.iter().find(|id| !held.contains(id)) {
            return Err(format!("cannot unload body {id}: it is not on this worker"));
        }
        // Groups losing members are dissolved; the master sends the new layout next.
        let mut out = Vec::with_capacity(ids.len());
        let take: std::collections::BTreeSet<u32> = ids.iter().copied().collect();
        let mut kept = Vec::new();
        for g in self.groups.drain(..) {
            if g.bodies.iter().any(|b| take.contains(&b.id)) {
                for b in g.bodies {
                    if take.contains(&b.id) {
                        out.push(b);
                    } else {
                        self.loose.push(b);
                    }
                }
            } else {
                kept.push(g);
            }
        }
        self.groups = kept;
        let (gone, stay): (Vec<Body>, Vec<Body>) =
            self.loose.drain(..).partition(|b| take.contains(&b.id));
        self.loose = stay;
        out.extend(gone);
        out.sort_by_key(|b| b.id);
        Ok(Reply::Unloaded(out))
    }

    fn regroup(&mut self, layout: Vec<Vec<u32>>) -> Result<Reply, String> {
        let mut listed = std::collections::BTreeSet::new();
        for id in layout.iter().flatten() {
            if !listed.insert(*id) {
                return Err(format!("regroup lists body {id} twice"));
            }
        }
        let held: std::collections::BTreeSet<u32> = self.ids().collect();
        if listed != held {
            let missing: Vec<u32> = listed.difference(&held).copied().collect();
            let extra: Vec<u32> = held.difference(&listed).copied().collect();
            return Err(format!(
                "regroup does not match the bodies held: not here {missing:?}, not placed {extra:?}"
            ));
        }
        let mut layout = layout;
        for g in &mut layout {
            g.sort_unstable();
        }
        layout.retain(|g| !g.is_empty());
        layout.sort_by_key(|g| g.first().copied());
        // Groups whose membership is unchanged are kept as they are (with their
        // contact search caches); the others are rebuilt from their bodies.
        let wanted: std::collections::BTreeSet<&[u32]> = layout.iter().map(Vec::as_slice).collect();
        let mut keep: BTreeMap<Vec<u32>, Group> = BTreeMap::new();
        let mut rest = Vec::new();
        for g in self.groups.drain(..) {
            let ids: Vec<u32> = g.bodies.iter().map(|b| b.id).collect();
            if wanted.contains(ids.as_slice()) {
                keep.insert(ids, g);
            } else {
                rest.push(g);
            }
        }
        self.groups = rest;
        let mut pool = self.pool();
        let mut groups = Vec::with_capacity(layout.len());
        for ids in layout {
            if let Some(g) = keep.remove(&ids) {
                groups.push(g);
                continue;
            }
            let bodies = ids.iter().filter_map(|id| pool.remove(id)).collect();
            groups.push(self.new_group(bodies)?);
        }
        self.groups = groups;
        Ok(Reply::Ack)
    }

    /// Run `f` on every group in parallel; reports in group order, the fault of the
    /// first faulting group (smallest body id) if any.
    fn run(
        &mut self,
        f: impl Fn(&mut Group) -> Result<Vec<BodyReport>, Fault> + Sync + Send,
    ) -> Reply {
        if self.broken {
            return Reply::Error("a fault stopped this worker's groups".into());
        }
        if !self.loose.is_empty() {
            return Reply::Error(format!(
                "{} bodies were loaded but not placed in a group",
                self.loose.len()
            ));
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
        };
        for (g, (r, nanos)) in self.groups.iter().zip(results) {
            let first = g.bodies.first().map_or(0, |b| b.id);
            match r {
                Ok(reports) => {
                    rep.bodies.extend(reports);
                    rep.contacts.extend_from_slice(g.contact_stats());
                }
                Err(fault) => {
                    self.broken = true;
                    return Reply::Fault {
                        group_first: first,
                        fault,
                    };
                }
            }
            rep.groups.push(GroupTime { first, nanos });
        }
        rep.compute_ns = t0.elapsed().as_nanos() as u64;
        Reply::Report(rep)
    }

    /// Copies of every body held, sorted by id.
    pub fn snapshot(&self) -> Vec<Body> {
        let mut out: Vec<Body> = self
            .groups
            .iter()
            .flat_map(|g| g.bodies.iter())
            .chain(&self.loose)
            .cloned()
            .collect();
        out.sort_by_key(|b| b.id);
        out
    }
}
