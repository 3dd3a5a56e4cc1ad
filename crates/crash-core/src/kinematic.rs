//! The integration step of a kinematic body (every DOF of every node prescribed): its
//! new velocities are its programs' values over the step, so the node loop of
//! `integrate.rs` reduces to x_{n+1} = x_n + h v_{n+1/2} plus the sums the body reports.
//! The programs are evaluated once per step instead of once per node (a program is a
//! function of the clock only: the same bits), and nothing is gathered: the force slots
//! and contact forces of a kinematic body never move it (the work contact does on it is
//! counted per pair, `PairStats::kin_a`, `KinematicWork`, so that it does not depend on
//! which group holds which copy).
//!
//! A read-only copy (`Group::copies`) reports nothing: `copy_step` moves the nodes and
//! gives the box, the largest move and the finiteness check, and leaves the energy
//! record alone. Both give the motion bits of `Body::integrate`'s general loop, and the
//! owner's path its energy bits too (the terms that are zero for a kinematic body are
//! kept where a NaN could flow through them).

use crate::body::{Body, NO_PROGRAM};
use crate::error::Fault;
use crate::forces::CHUNK;
use crate::integrate::{node_chunks, NodeSums, StepClock};
use crate::Vec3;

impl Body {
    /// Half-step velocity and angular velocity of each program over the step of `clock`,
    /// then (last) those of a node without a program (held at rest).
    fn program_table(&self, clock: &StepClock) -> Vec<(Vec3, Vec3)> {
        let d = &*self.def;
        d.programs
            .iter()
            .map(|p| p.over_step(clock.t, clock.h, &d.curves))
            .chain(std::iter::once((Vec3::zeros(), Vec3::zeros())))
            .collect()
    }

    /// `Body::integrate` of a kinematic body (`BodyDef::kinematic`), energies and
    /// reactions included.
    pub(crate) fn integrate_kinematic(
        &mut self,
        clock: &StepClock,
        gravity: Vec3,
    ) -> Result<NodeSums, Fault> {
        self.kinematic_step(clock, gravity, true)
    }

    /// The step of a read-only copy of a kinematic body: the motion and the box, largest
    /// move and finiteness of `Body::integrate`, no energy record (a copy's energies are
    /// never reported: its owner's are). A body that is not kinematic takes the general
    /// step.
    pub fn copy_step(&mut self, clock: &StepClock, gravity: Vec3) -> Result<NodeSums, Fault> {
        if !self.def.kinematic {
            return self.integrate(clock, gravity);
        }
        self.kinematic_step(clock, gravity, false)
    }

    fn kinematic_step(
        &mut self,
        clock: &StepClock,
        gravity: Vec3,
        energy: bool,
    ) -> Result<NodeSums, Fault> {
        let h = clock.h;
        let hbar = 0.5 * (clock.h_prev + h);
        let c = self.def.mass_damping;
        let (dn, dd) = (1.0 - 0.5 * c * hbar, 1.0 / (1.0 + 0.5 * c * hbar));
        let table = self.program_table(clock);
        let rest = table.len() - 1;
        let d = &*self.def;
        let (mass, inertia, program) = (&d.mass, &d.inertia, &d.program);
        // with Kelvin damping the integration books the (zero) Kelvin work of the slots
        let kelvin =
            d.slot_count() > d.gather_slot.len() && self.state.slots.len() >= d.slot_count();
        let t = clock.t;
        // the chunks and their merge of `Body::integrate` (the sums' bits)
        let (x, v, w) = (&mut self.state.x, &mut self.state.v, &mut self.state.w);
        let parts = node_chunks(x, v, w, d.halo_nodes, |ci, xs, vs, ws| {
            let mut s = NodeSums::default();
            for k in 0..xs.len() {
                let i = ci * CHUNK + k;
                let p = match program[i] {
                    NO_PROGRAM => rest,
                    p => p as usize,
                };
                let (v_new, w_new) = table[p];
                if energy {
                    let m = mass[i];
                    let inr = inertia[i];
                    let (f, mom) = d.external_at(i, gravity * m, t);
                    let (v_old, w_old) = (vs[k], ws[k]);
                    let free_v = (v_old * dn + f * (hbar / m)) * dd;
                    let free_w = (w_old * dn + mom * (hbar / inr)) * dd;
                    let vn = (v_old + v_new) * 0.5;
                    let wn = (w_old + w_new) * 0.5;
                    let zero = Vec3::zeros();
                    s.kinetic += 0.5 * (m * v_new.norm_squared() + inr * w_new.norm_squared());
                    s.external += hbar * (f.dot(&vn) + mom.dot(&wn));
                    s.contact += hbar * zero.dot(&vn);
                    s.internal_power += zero.dot(&v_new) + zero.dot(&w_new);
                    if kelvin {
                        s.kelvin += hbar * (zero.dot(&vn) + zero.dot(&wn));
                        s.internal_power -= zero.dot(&v_new) + zero.dot(&w_new);
                    }
                    // xs[k] is still x_n, the position the reaction acts at
                    let dv = (v_new - free_v, w_new - free_w);
                    s.add_reaction((m, inr), dv, dd, (vn, wn), hbar, &xs[k]);
                    s.add_damping(c, hbar, (m, inr), (vn, wn));
                }
                s.advance(i, h, (&mut xs[k], &mut vs[k], &mut ws[k]), v_new, w_new);
            }
            s
        });
        let total = NodeSums::total(&parts, clock.step, self.def.id)?;
        if energy {
            self.book(h, &total);
        }
        Ok(total)
    }
}
