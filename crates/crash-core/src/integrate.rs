//! Pipeline stage: gather element forces per node in a fixed order and advance by the
//! central-difference scheme of the seed, eq. (5)–(6), with a variable step:
//!   a_n = M^-1 (F_ext + F_c - F_int)
//!   v_{n+1/2} = v_{n-1/2} + hbar_n a_n,  hbar_n = (h_{n-1/2} + h_{n+1/2}) / 2
//!   x_{n+1}   = x_n + h_{n+1/2} v_{n+1/2}
//! At the start h_{-1/2} = 0, which gives the seed's V_{1/2} = V_0 + h A_0 / 2.
//! Mass damping c (f = -c m v_n, v_n the mean of the two half-step velocities) is
//! integrated implicitly: v_{n+1/2} = ((1 - c hbar/2) v_{n-1/2} + hbar a) / (1 + c hbar/2).

use crate::body::{Body, BodyDef, NO_PROGRAM};
use crate::contact::figures::{ChunkFigures, NodeFigures};
use crate::contact::sweep::Momentum;
use crate::element::simd::prefetch;
use crate::error::Fault;
use crate::forces::CHUNK;

/// How many nodes ahead the integration prefetches force slots.
const PREFETCH: usize = 8;
use crate::Vec3;
use rayon::prelude::*;

/// Per-body sums of the node loop.
#[derive(Debug, Clone, Copy)]
pub struct NodeSums {
    /// Kinetic energy of v_{n+1/2}: with work increments hbar f_n . (v_{n-1/2} + v_{n+1/2})/2
    /// it telescopes exactly (m (v+ - v-) . (v+ + v-)/2 = hbar f . v_mean).
    pub kinetic: f64,
    /// Work increments over this step: loads and gravity, boundary reactions, contact
    /// forces (on this body), mass damping (dissipated, >= 0).
    pub external: f64,
    pub reaction: f64,
    /// Force and moment the constraints exert on the body at t_n (sum over its
    /// constrained DOFs of the impulse they apply over hbar, divided by hbar).
    pub reaction_force: Vec3,
    pub reaction_moment: Vec3,
    /// The reactions' resultant moment about the origin: sum x_n x F + reaction_moment.
    pub reaction_moment_origin: Vec3,
    pub contact: f64,
    pub mass_damping: f64,
    /// Work of the Kelvin (element viscous) forces f_d of the pass at x_n,
    /// hbar f_d . (v_{n-1/2} + v_{n+1/2})/2 (dissipated): the time levels of the
    /// kinetic energy's telescoping, so the damping column closes the balance exactly.
    pub kelvin: f64,
    /// (f_int - f_d)(x_n) . v_{n+1/2} (forces and moments; f_d the Kelvin part, booked
    /// in `kelvin`), for the shadow internal energy.
    pub internal_power: f64,
    /// Largest nodal displacement in this step and its node.
    pub max_move: f64,
    pub max_move_node: usize,
    /// Bounding box of the new positions.
    pub lo: Vec3,
    pub hi: Vec3,
    /// First node with a non-finite state.
    pub bad_node: Option<usize>,
}

impl Default for NodeSums {
    fn default() -> Self {
        Self {
            kinetic: 0.0,
            external: 0.0,
            reaction: 0.0,
            reaction_force: Vec3::zeros(),
            reaction_moment: Vec3::zeros(),
            reaction_moment_origin: Vec3::zeros(),
            contact: 0.0,
            mass_damping: 0.0,
            kelvin: 0.0,
            internal_power: 0.0,
            max_move: 0.0,
            max_move_node: 0,
            lo: Vec3::repeat(f64::INFINITY),
            hi: Vec3::repeat(f64::NEG_INFINITY),
            bad_node: None,
        }
    }
}

impl NodeSums {
    pub(crate) fn merge(mut self, o: &NodeSums) -> Self {
        self.kinetic += o.kinetic;
        self.external += o.external;
        self.reaction += o.reaction;
        self.reaction_force += o.reaction_force;
        self.reaction_moment += o.reaction_moment;
        self.reaction_moment_origin += o.reaction_moment_origin;
        self.contact += o.contact;
        self.mass_damping += o.mass_damping;
        self.kelvin += o.kelvin;
        self.internal_power += o.internal_power;
        if o.max_move > self.max_move {
            self.max_move = o.max_move;
            self.max_move_node = o.max_move_node;
        }
        self.lo = self.lo.inf(&o.lo);
        self.hi = self.hi.sup(&o.hi);
        if self.bad_node.is_none() {
            self.bad_node = o.bad_node;
        }
        self
    }
}

impl BodyDef {
    /// Gravity's force `g` on node i plus its nodal loads at time t: (force, moment).
    #[inline(always)]
    pub(crate) fn external_at(&self, i: usize, g: Vec3, t: f64) -> (Vec3, Vec3) {
        let mut f = g;
        let mut mom = Vec3::zeros();
        let first = self.load_of[i];
        if first != u32::MAX {
            for l in self.loads[first as usize..]
                .iter()
                .take_while(|l| l.node as usize == i)
            {
                let sc = l.scale(t, &self.curves);
                f += l.force * sc;
                mom += l.moment * sc;
            }
        }
        (f, mom)
    }
}

impl NodeSums {
    /// Node i's reaction terms: the impulses the constraints applied over the step
    /// (mass and inertia (m, inr) times the velocity changes `dv` they made, over the
    /// implicit damping factor `dd`), the mean velocities (vn, wn), x_n where they act.
    #[inline(always)]
    pub(crate) fn add_reaction(
        &mut self,
        (m, inr): (f64, f64),
        dv: (Vec3, Vec3),
        dd: f64,
        (vn, wn): (Vec3, Vec3),
        hbar: f64,
        x: &Vec3,
    ) {
        let (jf, jm) = (m * dv.0 * dd.recip(), inr * dv.1 * dd.recip());
        self.reaction += jf.dot(&vn) + jm.dot(&wn);
        let (rf, rm) = (jf / hbar, jm / hbar);
        self.reaction_force += rf;
        self.reaction_moment += rm;
        self.reaction_moment_origin += x.cross(&rf) + rm;
    }

    /// Work of the mass damping c over the step at the mean velocities (dissipated).
    #[inline(always)]
    pub(crate) fn add_damping(
        &mut self,
        c: f64,
        hbar: f64,
        (m, inr): (f64, f64),
        (vn, wn): (Vec3, Vec3),
    ) {
        if c > 0.0 {
            self.mass_damping += hbar * c * (m * vn.norm_squared() + inr * wn.norm_squared());
        }
    }

    /// x_{n+1} = x_n + h v_{n+1/2} for node i, with its new velocities stored; the box
    /// and largest move grow. A non-finite result is recorded (`bad_node`) and stores
    /// nothing.
    #[inline(always)]
    pub(crate) fn advance(
        &mut self,
        i: usize,
        h: f64,
        (x, v, w): (&mut Vec3, &mut Vec3, &mut Vec3),
        v_new: Vec3,
        w_new: Vec3,
    ) {
        let dx = v_new * h;
        let xn = *x + dx;
        let mv = dx.norm();
        if !(mv.is_finite()
            && xn.x.is_finite()
            && xn.y.is_finite()
            && xn.z.is_finite()
            && w_new.x.is_finite()
            && w_new.y.is_finite()
            && w_new.z.is_finite())
        {
            if self.bad_node.is_none() {
                self.bad_node = Some(i);
            }
            return;
        }
        if mv > self.max_move {
            self.max_move = mv;
            self.max_move_node = i;
        }
        self.lo = self.lo.inf(&xn);
        self.hi = self.hi.sup(&xn);
        *x = xn;
        *v = v_new;
        *w = w_new;
    }

    /// The chunks' sums merged in chunk order, or the fault of the first bad node.
    pub(crate) fn total(parts: &[NodeSums], step: u64, body: u32) -> Result<NodeSums, Fault> {
        let total = parts.iter().fold(NodeSums::default(), |a, b| a.merge(b));
        match total.bad_node {
            Some(n) => Err(Fault::NonFinite {
                step,
                body,
                place: format!("node {n}"),
                what: "velocity or position",
            }),
            None => Ok(total),
        }
    }
}

/// `f(chunk index, x, v, w)` over the nodes' chunks of `CHUNK` on the pool, the sums in
/// chunk order; single chunks, for an even end of the loop on every thread (forces.rs).
/// The last `halo` nodes (a part's halo nodes, which take their state from their
/// owner) are left out.
pub(crate) fn node_chunks<R: Send>(
    x: &mut [Vec3],
    v: &mut [Vec3],
    w: &mut [Vec3],
    halo: usize,
    f: impl Fn(usize, &mut [Vec3], &mut [Vec3], &mut [Vec3]) -> R + Sync + Send,
) -> Vec<R> {
    let n = x.len().saturating_sub(halo);
    let (x, v, w) = (&mut x[..n], &mut v[..n], &mut w[..n]);
    x.par_chunks_mut(CHUNK)
        .zip(v.par_chunks_mut(CHUNK))
        .zip(w.par_chunks_mut(CHUNK))
        .enumerate()
        .with_max_len(1)
        .map(|(ci, ((xs, vs), ws))| f(ci, xs, vs, ws))
        .collect()
}

/// Time and step data of one integration step.
#[derive(Debug, Clone, Copy)]
pub struct StepClock {
    /// t_n.
    pub t: f64,
    /// h_{n-1/2} (0 at the first step).
    pub h_prev: f64,
    /// h_{n+1/2}.
    pub h: f64,
    pub step: u64,
}

impl Body {
    /// Advance the nodes of this body from x_n to x_{n+1} (all but a part's halo nodes).
    pub fn integrate(&mut self, clock: &StepClock, gravity: Vec3) -> Result<NodeSums, Fault> {
        self.integrate_taking(clock, gravity, false).map(|(s, _)| s)
    }

    /// `integrate`, with the contact stage's figures of the new nodes taken in the same
    /// loop (`contact::figures`) for a whole, deformable contact body (None otherwise).
    pub fn integrate_with_figures(
        &mut self,
        clock: &StepClock,
        gravity: Vec3,
    ) -> Result<(NodeSums, Option<NodeFigures>), Fault> {
        self.integrate_taking(clock, gravity, true)
    }

    fn integrate_taking(
        &mut self,
        clock: &StepClock,
        gravity: Vec3,
        figures: bool,
    ) -> Result<(NodeSums, Option<NodeFigures>), Fault> {
        if self.def.kinematic {
            // the same bits without the per-node program and force terms (kinematic.rs)
            return Ok((self.integrate_kinematic(clock, gravity)?, None));
        }
        // the momentum's scale needs the whole body's mass first (a sum in node order)
        let taking = figures && self.def.contact && self.def.halo_nodes == 0;
        let mass_scale = taking.then(|| {
            let m = self.total_mass();
            (m, Momentum::scale(m))
        });
        let scale = mass_scale.map(|(_, sc)| sc);
        let h = clock.h;
        let hbar = 0.5 * (clock.h_prev + h);
        let c = self.def.mass_damping;
        let (dn, dd) = (1.0 - 0.5 * c * hbar, 1.0 / (1.0 + 0.5 * c * hbar));
        let gs = &self.def.gather_start;
        let gi = &self.def.gather_slot;
        // the force slots and, with Kelvin damping, the Kelvin part of each (empty
        // otherwise: an undamped body reads nothing more)
        let (slots, kelvin) = self.state.slots.split_at(gi.len());
        let kelvin = kelvin
            .get(..self.def.slot_count() - gi.len())
            .unwrap_or_default();
        let fc = &self.state.f_contact;
        let d = &*self.def;
        let programs = &self.def.programs;
        let curves = &self.def.curves;
        let (mass, inertia, fixed, program) = (
            &self.def.mass,
            &self.def.inertia,
            &self.def.fixed,
            &self.def.program,
        );
        let t = clock.t;
        let (x, v, w) = (&mut self.state.x, &mut self.state.v, &mut self.state.w);
        let parts = node_chunks(x, v, w, self.def.halo_nodes, |ci, xs, vs, ws| {
            let mut s = NodeSums::default();
            for k in 0..xs.len() {
                let i = ci * CHUNK + k;
                // the force slots of a node a few places ahead (see `prefetch`)
                if let Some(range) = gs.get(i + PREFETCH..i + PREFETCH + 2) {
                    for &sl in &gi[range[0] as usize..range[1] as usize] {
                        // a 48-byte slot starts at byte 0, 16, 32 or 48 of a
                        // line: it may end on the next one
                        let q = &slots[sl as usize];
                        prefetch(&q[0]);
                        prefetch(&q[5]);
                    }
                }
                let m = mass[i];
                let inr = inertia[i];
                // forces: external (gravity, loads), contact, minus internal
                let (mut f, mut mom) = d.external_at(i, gravity * m, t);
                let (fe, me) = (f, mom);
                let mut fcon = Vec3::zeros();
                if !fc.is_empty() {
                    fcon = fc[i];
                    f += fcon;
                }
                let mut fi = Vec3::zeros();
                let mut mi = Vec3::zeros();
                let mut fd = Vec3::zeros();
                let mut md = Vec3::zeros();
                for &sl in &gi[gs[i] as usize..gs[i + 1] as usize] {
                    let q = &slots[sl as usize];
                    fi += Vec3::new(q[0], q[1], q[2]);
                    mi += Vec3::new(q[3], q[4], q[5]);
                }
                f -= fi;
                mom -= mi;
                if !kelvin.is_empty() {
                    for &sl in &gi[gs[i] as usize..gs[i + 1] as usize] {
                        let q = &kelvin[sl as usize];
                        fd += Vec3::new(q[0], q[1], q[2]);
                        md += Vec3::new(q[3], q[4], q[5]);
                    }
                }
                let v_old = vs[k];
                let w_old = ws[k];
                let mut v_new = (v_old * dn + f * (hbar / m)) * dd;
                let mut w_new = (w_old * dn + mom * (hbar / inr)) * dd;
                let free_v = v_new;
                let free_w = w_new;
                let fx = fixed[i];
                if fx != 0 {
                    let (pv, pw) = match program[i] {
                        NO_PROGRAM => (Vec3::zeros(), Vec3::zeros()),
                        p => programs[p as usize].over_step(t, h, curves),
                    };
                    for d in 0..3 {
                        if fx & (1 << d) != 0 {
                            v_new[d] = pv[d];
                        }
                        if fx & (8 << d) != 0 {
                            w_new[d] = pw[d];
                        }
                    }
                }
                let vn = (v_old + v_new) * 0.5;
                let wn = (w_old + w_new) * 0.5;
                s.kinetic += 0.5 * (m * v_new.norm_squared() + inr * w_new.norm_squared());
                s.external += hbar * (fe.dot(&vn) + me.dot(&wn));
                s.contact += hbar * fcon.dot(&vn);
                s.internal_power += fi.dot(&v_new) + mi.dot(&w_new);
                if !kelvin.is_empty() {
                    // the Kelvin force's work at the kinetic energy's time levels;
                    // the shadow internal energy takes the elastic part only
                    s.kelvin += hbar * (fd.dot(&vn) + md.dot(&wn));
                    s.internal_power -= fd.dot(&v_new) + md.dot(&w_new);
                }
                if fx != 0 {
                    // impulse the constraint applied, times the mean velocity
                    // xs[k] is still x_n, the position the reaction acts at
                    let dv = (v_new - free_v, w_new - free_w);
                    s.add_reaction((m, inr), dv, dd, (vn, wn), hbar, &xs[k]);
                }
                s.add_damping(c, hbar, (m, inr), (vn, wn));
                s.advance(i, h, (&mut xs[k], &mut vs[k], &mut ws[k]), v_new, w_new);
            }
            // the chunk is still in the cache: the contact stage's figures of it
            let at = ci * CHUNK;
            let fig =
                scale.map(|sc| ChunkFigures::of(s.lo, s.hi, vs, &mass[at..at + vs.len()], sc));
            (s, fig)
        });
        let (sums, figs): (Vec<NodeSums>, Vec<Option<ChunkFigures>>) = parts.into_iter().unzip();
        let total = NodeSums::total(&sums, clock.step, self.def.id)?;
        self.book(h, &total);
        let figures = mass_scale.map(|(m, sc)| {
            let figs: Vec<ChunkFigures> = figs.into_iter().flatten().collect();
            NodeFigures::gather(&figs, m, sc, total.max_move, (total.lo, total.hi))
        });
        Ok((total, figures))
    }

    /// The step's sums into the energy record (a step of length h).
    pub(crate) fn book(&mut self, h: f64, total: &NodeSums) {
        let e = &mut self.state.energy;
        e.kinetic = total.kinetic;
        // Shadow internal energy at t_{n+1/2}: E(x_n) + h/2 f_int(x_n) . v_{n+1/2}, which
        // equals x_n K x_{n+1} / 2 for a linear system, the quadratic form that central
        // differences conserve exactly (so the balance closes to round-off in the linear
        // undamped case, high frequencies included).
        e.internal = self.state.internal_now + 0.5 * h * total.internal_power;
        e.hourglass = self.state.hourglass_now;
        e.external += total.external + total.reaction;
        e.contact -= total.contact;
        e.damping += total.mass_damping + total.kelvin;
    }
}
