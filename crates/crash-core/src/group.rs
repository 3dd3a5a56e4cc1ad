//! The one-step pipeline of a group of bodies (the unit a worker owns):
//! integrate (x_n -> x_{n+1}) -> element forces at x_{n+1} -> contact at x_{n+1}
//! (contact last: its soft penalty uses this pass's element critical steps).
//! Forces are thus ready before the next step's time step is chosen, and the stable dt
//! reported is that of the configuration the next step starts from.

use crate::body::{Body, BodyEnergy};
use crate::clock::Clock;
use crate::contact::figures::NodeFigures;
use crate::contact::stage::Given;
use crate::contact::{ContactConfig, ContactState, PairStats};
use crate::error::Fault;
use crate::forces::ForceSums;
use crate::probe::{nodes_of, NodeProbe};
use crate::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// What one body reports after a step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BodyReport {
    pub id: u32,
    /// Energies at t_{n+1/2} (see `BodyEnergy`).
    pub energy: BodyEnergy,
    /// Critical element time step of the new configuration (no safety factor).
    pub stable_dt: f64,
    pub dt_element: usize,
    pub lo: Vec3,
    pub hi: Vec3,
    pub max_move: f64,
    pub hot_element: usize,
    pub hot_density: f64,
    /// What the supports exert on the body at t_n (LS-DYNA SPCFORC), when the group
    /// reports reactions and the body has constrained DOFs.
    pub reaction: Option<Reaction>,
}

/// Resultants of the support reactions on one body at t_n.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Reaction {
    /// Sum of the nodal reaction forces F_i [N].
    pub force: Vec3,
    /// Sum of the rotational-DOF reaction moments m_i [N m].
    pub moment: Vec3,
    /// Resultant moment about the global origin [N m]: sum x_i(t_n) x F_i + sum m_i.
    pub moment_origin: Vec3,
}

impl BodyReport {
    /// A placeholder for body `id` before its first report (zero energies and box).
    pub fn empty(id: u32) -> Self {
        Self {
            id,
            energy: BodyEnergy::default(),
            stable_dt: f64::INFINITY,
            dt_element: 0,
            lo: Vec3::zeros(),
            hi: Vec3::zeros(),
            max_move: 0.0,
            hot_element: 0,
            hot_density: 0.0,
            reaction: None,
        }
    }
}

/// Which optional figures a step reports (each only when the group has it on):
/// the master asks for them on the steps whose result rows are due.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Due {
    /// Support reactions (spcforc.csv).
    pub reactions: bool,
    /// History nodes (nodout.csv).
    pub probes: bool,
}

impl Due {
    pub const ALL: Due = Due {
        reactions: true,
        probes: true,
    };
}

/// A set of bodies integrated together.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Group {
    pub bodies: Vec<Body>,
    pub gravity: Vec3,
    /// Contact parameters.
    #[serde(default)]
    pub contact: ContactConfig,
    /// Contact search caches and the last pass's statistics: not physical state,
    /// rebuilt lazily (results never depend on them).
    #[serde(skip)]
    pub contact_state: ContactState,
    /// Ids (sorted) of the bodies in `bodies` that are read-only copies of kinematic
    /// bodies owned elsewhere: advanced by their prescribed law like the owner (the same
    /// bits: integration of a kinematic body depends only on its state, the clock and
    /// its definition), in contact with this group's bodies, never reported.
    #[serde(default)]
    pub copies: Vec<u32>,
    /// Report the supports' reactions (`BodyReport::reaction`).
    #[serde(default)]
    pub reactions: bool,
    /// History nodes (body id, node index), sorted: their rows after each step are in
    /// `probed` (outputs off: both empty, nothing is done).
    #[serde(default)]
    pub probes: Vec<(u32, u32)>,
    #[serde(skip)]
    pub probed: Vec<NodeProbe>,
    /// Wall time per stage of `advance` (a measurement, not state).
    #[serde(skip)]
    pub times: StageTimes,
}

/// Wall time spent in each stage of `Group::advance` since the group was made: the
/// per-stage figures of the benchmarks (two clock reads per stage and step).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Central-difference update of velocities and positions (with the constraints).
    pub integrate: Duration,
    /// Element internal forces and energies.
    pub elements: Duration,
    /// The contact pass: search, crossing check, penalty forces.
    pub contact: Duration,
    /// Steps timed.
    pub steps: u64,
}

/// An energy or a stable time step that overflowed is a blow-up of this body, reported
/// here as a fault: a master then takes any non-finite number in a report for a
/// worker's lie (crash-master `plausible.rs`), never for physics.
fn finite_reports(out: &[BodyReport], step: u64) -> Result<(), Fault> {
    for r in out {
        let e = &r.energy;
        let bad = [
            ("kinetic energy", e.kinetic),
            ("internal energy", e.internal),
            ("hourglass energy", e.hourglass),
            ("contact energy", e.contact),
            ("damping energy", e.damping),
            ("external work", e.external),
            ("stable time step", r.stable_dt),
        ]
        .into_iter()
        .find(|(what, v)| v.is_nan() || (v.is_infinite() && *what != "stable time step"));
        if let Some((what, _)) = bad {
            return Err(Fault::NonFinite {
                step,
                body: r.id,
                place: format!("element {}", r.hot_element),
                what,
            });
        }
    }
    Ok(())
}

/// Bodies below this many elements go to the pool as a whole, side by side (a floor's
/// spheres: one or two chunks each, which one after the other paid a fork-join apiece);
/// larger ones run one after the other, each split in chunks on the pool (two large
/// bodies side by side ran the showcase's stages 10-20 % slower on 2 threads).
const WHOLE_ON_POOL_BELOW: usize = 8 * crate::forces::CHUNK;

/// `f` on every body, results in body order: the large bodies one after the other, the
/// small ones side by side on the pool. A body's result depends on its own state only,
/// so the bits are those of a plain loop.
fn each_body<R: Send>(bodies: &mut [Body], f: impl Fn(&mut Body) -> R + Sync) -> Vec<R> {
    let small = |b: &Body| b.def.element_count() < WHOLE_ON_POOL_BELOW;
    let mut out: Vec<Option<R>> = bodies.iter().map(|_| None).collect();
    for (b, o) in bodies.iter_mut().zip(out.iter_mut()) {
        if !small(b) {
            *o = Some(f(b));
        }
    }
    // no pool dispatch per stage and step for groups of large bodies only (the showcase)
    if bodies.iter().any(small) {
        bodies
            .par_iter_mut()
            .zip(out.par_iter_mut())
            .filter(|(b, _)| small(b))
            .for_each(|(b, o)| *o = Some(f(b)));
    }
    out.into_iter().flatten().collect()
}

fn report(b: &Body, f: &ForceSums, lo: Vec3, hi: Vec3, max_move: f64) -> BodyReport {
    BodyReport {
        id: b.def.id,
        energy: b.state.energy,
        stable_dt: f.dt,
        dt_element: f.dt_element,
        lo,
        hi,
        max_move,
        hot_element: f.hot_element,
        hot_density: f.hot_density,
        reaction: None,
    }
}

impl Group {
    pub fn new(bodies: Vec<Body>, gravity: Vec3) -> Self {
        Self {
            bodies,
            gravity,
            contact: ContactConfig::default(),
            contact_state: ContactState::default(),
            copies: Vec::new(),
            reactions: false,
            probes: Vec::new(),
            probed: Vec::new(),
            times: StageTimes::default(),
        }
    }

    /// A group of `bodies` plus read-only `copies` of kinematic bodies; the bodies are
    /// kept in id order.
    pub fn with_copies(mut bodies: Vec<Body>, copies: Vec<Body>, gravity: Vec3) -> Self {
        let mut ids: Vec<u32> = copies.iter().map(|b| b.def.id).collect();
        ids.sort_unstable();
        bodies.extend(copies);
        bodies.sort_by_key(|b| b.def.id);
        let mut g = Self::new(bodies, gravity);
        g.copies = ids;
        g
    }

    /// Whether body `id` is a read-only copy here.
    pub fn is_copy(&self, id: u32) -> bool {
        self.copies.binary_search(&id).is_ok()
    }

    /// The bodies this group owns (not copies), in id order.
    pub fn owned(&self) -> impl Iterator<Item = &Body> {
        self.bodies.iter().filter(|b| !self.is_copy(b.def.id))
    }

    /// Smallest id of an owned body (the group's name in reports and faults).
    pub fn first(&self) -> u32 {
        self.owned().next().map_or(0, |b| b.def.id)
    }

    /// Reports of the owned bodies only.
    fn owned_reports(&self, mut out: Vec<BodyReport>) -> Vec<BodyReport> {
        if !self.copies.is_empty() {
            out.retain(|r| !self.is_copy(r.id));
        }
        out
    }

    /// History rows of the last step (or of the start), body after body.
    pub fn probed(&self) -> &[NodeProbe] {
        &self.probed
    }

    /// Contact forces at the current positions; lowers each report's stable dt where
    /// contact requires it.
    /// `h`, `step`: the step that led here (0, 0 at the start), for the crossing check.
    /// `figures`: what the step's integration took of each body's nodes (empty at the
    /// start).
    fn contact_pass(
        &mut self,
        out: &mut [BodyReport],
        h: f64,
        step: u64,
        figures: &[Option<NodeFigures>],
    ) -> Result<(), Fault> {
        let dts: Vec<f64> = out.iter().map(|r| r.stable_dt).collect();
        // the reports' boxes are the bodies' node boxes at these positions
        let boxes: Vec<_> = out.iter().map(|r| (r.lo, r.hi)).collect();
        let given = Given {
            closing: None,
            figures,
            counted: &[],
            counted_segments: &[],
            slave_segments: &[],
        };
        let limit = crate::contact::stage::contact_forces_given(
            &mut self.bodies,
            &self.contact,
            &mut self.contact_state,
            &dts,
            &boxes,
            h,
            step,
            given,
        )?;
        for (r, d) in out.iter_mut().zip(limit) {
            r.stable_dt = r.stable_dt.min(d);
        }
        Ok(())
    }

    /// Per body pair contact statistics of the last force pass, sorted by pair.
    pub fn contact_stats(&self) -> &[PairStats] {
        self.contact_state.stats()
    }

    /// Forces at the initial configuration (no rate increments).
    pub fn start(&mut self) -> Result<Vec<BodyReport>, Fault> {
        let mut out = Vec::with_capacity(self.bodies.len());
        for b in &mut self.bodies {
            b.apply_constraints(0.0);
            let f = b.internal_forces(0.0, 0)?;
            let (lo, hi) = crate::mesh::bounds(&b.state.x);
            b.state.energy.internal = b.state.internal_now;
            b.state.energy.hourglass = b.state.hourglass_now;
            b.state.energy.kinetic = b.kinetic_energy_now();
            out.push(report(b, &f, lo, hi, 0.0));
        }
        self.probed.clear();
        for b in &self.bodies {
            let nodes = nodes_of(&self.probes, b.def.id);
            if !nodes.is_empty() {
                let v = b.probe_velocities(nodes);
                b.probe(nodes, &v, 0.0, &mut self.probed);
            }
        }
        self.contact_pass(&mut out, 0.0, 0, &[])?;
        finite_reports(&out, 0)?;
        Ok(self.owned_reports(out))
    }

    /// One step of length h from `clock` (the run's clock, owned by its loop): returns
    /// one report per owned body, in the group's body order, with the reactions and
    /// history nodes that are on.
    pub fn advance(&mut self, clock: &Clock, h: f64) -> Result<Vec<BodyReport>, Fault> {
        self.advance_with(clock, h, Due::ALL)
    }

    /// `advance`, reporting reactions and history nodes only where `due` says so (they
    /// change nothing else: a result row follows this step or not).
    pub fn advance_with(
        &mut self,
        clock: &Clock,
        h: f64,
        due: Due,
    ) -> Result<Vec<BodyReport>, Fault> {
        let sc = clock.step_of(h);
        let mut sums = Vec::with_capacity(self.bodies.len());
        self.probed.clear();
        let hbar = 0.5 * (sc.h_prev + sc.h);
        let t0 = Instant::now();
        let probes: &[(u32, u32)] = if due.probes { &self.probes } else { &[] };
        // small bodies go to the pool side by side (`each_body`); faults and probe rows
        // are taken in body order: same bits
        let gravity = self.gravity;
        let copies = &self.copies;
        let contact = self.contact.enabled;
        let stepped = each_body(&mut self.bodies, |b| {
            let before = b.probe_velocities(nodes_of(probes, b.def.id));
            // a copy's energies are never reported: its owner's are (kinematic.rs)
            if copies.binary_search(&b.def.id).is_ok() {
                b.copy_step(&sc, gravity).map(|s| (s, None))
            } else if contact {
                b.integrate_with_figures(&sc, gravity)
            } else {
                b.integrate(&sc, gravity).map(|s| (s, None))
            }
            .map(|s| (s, before))
        });
        let mut figures = Vec::with_capacity(self.bodies.len());
        for (b, r) in self.bodies.iter().zip(stepped) {
            let ((s, fig), before) = r?;
            figures.push(fig);
            let nodes = nodes_of(probes, b.def.id);
            if !nodes.is_empty() {
                b.probe(nodes, &before, hbar, &mut self.probed);
            }
            sums.push(s);
        }
        let step = clock.after(h).step;
        let moves: Vec<(f64, usize)> = sums.iter().map(|s| (s.max_move, s.max_move_node)).collect();
        crate::contact::check_moves(&self.bodies, &self.contact, &moves, h, step)?;
        let t1 = Instant::now();
        let forces = each_body(&mut self.bodies, |b| b.internal_forces(h, step));
        let mut out = Vec::with_capacity(self.bodies.len());
        for ((b, s), f) in self.bodies.iter().zip(&sums).zip(forces) {
            let f = f?;
            let mut r = report(b, &f, s.lo, s.hi, s.max_move);
            if self.reactions && due.reactions && b.def.fixed.iter().any(|&m| m != 0) {
                r.reaction = Some(Reaction {
                    force: s.reaction_force,
                    moment: s.reaction_moment,
                    moment_origin: s.reaction_moment_origin,
                });
            }
            out.push(r);
        }
        let t2 = Instant::now();
        self.contact_pass(&mut out, h, step, &figures)?;
        let t3 = Instant::now();
        self.times.integrate += t1 - t0;
        self.times.elements += t2 - t1;
        self.times.contact += t3 - t2;
        self.times.steps += 1;
        finite_reports(&out, step)?;
        Ok(self.owned_reports(out))
    }
}
