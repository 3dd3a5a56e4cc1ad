//! The one-step pipeline of a group of bodies (the unit a worker owns):
//! integrate (x_n -> x_{n+1}) -> element forces at x_{n+1} -> contact at x_{n+1}
//! (contact last: its soft penalty uses this pass's element critical steps).
//! Forces are thus ready before the next step's time step is chosen, and the stable dt
//! reported is that of the configuration the next step starts from.

use crate::body::{Body, BodyEnergy};
use crate::contact::{ContactConfig, ContactState, PairStats};
use crate::error::Fault;
use crate::forces::ForceSums;
use crate::integrate::StepClock;
use crate::Vec3;
use serde::{Deserialize, Serialize};

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
}

/// A set of bodies integrated together.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Group {
    pub bodies: Vec<Body>,
    pub gravity: Vec3,
    /// t_n of the current positions.
    pub time: f64,
    pub step: u64,
    /// h_{n-1/2}: the last step taken (0 before the first).
    pub h_prev: f64,
    /// Contact parameters.
    #[serde(default)]
    pub contact: ContactConfig,
    /// Contact search caches and the last pass's statistics: not physical state,
    /// rebuilt lazily (results never depend on them).
    #[serde(skip)]
    pub contact_state: ContactState,
}

fn report(b: &Body, f: &ForceSums, lo: Vec3, hi: Vec3, max_move: f64) -> BodyReport {
    BodyReport {
        id: b.id,
        energy: b.energy,
        stable_dt: f.dt,
        dt_element: f.dt_element,
        lo,
        hi,
        max_move,
        hot_element: f.hot_element,
        hot_density: f.hot_density,
    }
}

impl Group {
    pub fn new(bodies: Vec<Body>, gravity: Vec3) -> Self {
        Self {
            bodies,
            gravity,
            time: 0.0,
            step: 0,
            h_prev: 0.0,
            contact: ContactConfig::default(),
            contact_state: ContactState::default(),
        }
    }

    /// Contact forces at the current positions; lowers each report's stable dt where
    /// contact requires it.
    fn contact_pass(&mut self, out: &mut [BodyReport]) {
        let dts: Vec<f64> = out.iter().map(|r| r.stable_dt).collect();
        let limit = crate::contact::contact_forces(
            &mut self.bodies,
            &self.contact,
            &mut self.contact_state,
            &dts,
        );
        for (r, d) in out.iter_mut().zip(limit) {
            r.stable_dt = r.stable_dt.min(d);
        }
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
            let (lo, hi) = crate::mesh::bounds(&b.x);
            b.energy.internal = b.internal_now;
            b.energy.hourglass = b.hourglass_now;
            b.energy.kinetic = b.kinetic_energy_now();
            out.push(report(b, &f, lo, hi, 0.0));
        }
        self.contact_pass(&mut out);
        Ok(out)
    }

    /// One step of length h: returns one report per body, in the group's body order.
    pub fn advance(&mut self, h: f64) -> Result<Vec<BodyReport>, Fault> {
        let clock = StepClock {
            t: self.time,
            h_prev: self.h_prev,
            h,
            step: self.step,
        };
        let mut sums = Vec::with_capacity(self.bodies.len());
        for b in &mut self.bodies {
            sums.push(b.integrate(&clock, self.gravity)?);
        }
        self.time += h;
        self.step += 1;
        self.h_prev = h;
        let moves: Vec<(f64, usize)> = sums.iter().map(|s| (s.max_move, s.max_move_node)).collect();
        crate::contact::check_moves(&self.bodies, &self.contact, &moves, h, self.step)?;
        let mut out = Vec::with_capacity(self.bodies.len());
        for (b, s) in self.bodies.iter_mut().zip(&sums) {
            let f = b.internal_forces(h, self.step)?;
            out.push(report(b, &f, s.lo, s.hi, s.max_move));
        }
        self.contact_pass(&mut out);
        Ok(out)
    }
}
