//! Pipeline stage: gather element forces per node in a fixed order and advance by the
//! central-difference scheme of the seed, eq. (5)–(6), with a variable step:
//!   a_n = M^-1 (F_ext + F_c - F_int)
//!   v_{n+1/2} = v_{n-1/2} + hbar_n a_n,  hbar_n = (h_{n-1/2} + h_{n+1/2}) / 2
//!   x_{n+1}   = x_n + h_{n+1/2} v_{n+1/2}
//! At the start h_{-1/2} = 0, which gives the seed's V_{1/2} = V_0 + h A_0 / 2.
//! Mass damping c (f = -c m v_n, v_n the mean of the two half-step velocities) is
//! integrated implicitly: v_{n+1/2} = ((1 - c hbar/2) v_{n-1/2} + hbar a) / (1 + c hbar/2).

use crate::body::{Body, BodyDef};
use crate::contact::figures::{ChunkFigures, NodeFigures};
use crate::contact::sweep::Momentum;
use crate::element::simd::dispatch;
use crate::error::Fault;
use crate::forces::CHUNK;
use crate::node_loop::{NodeChunk, NodeStep};
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
        let mass_scale = self.mass_scale(figures);
        let step = NodeStep::of(
            &self.def,
            (&self.state.slots, &self.state.node_sums),
            &self.state.f_contact,
            clock,
            gravity,
            mass_scale,
        );
        let (x, v, w) = (&mut self.state.x, &mut self.state.v, &mut self.state.w);
        let parts = node_chunks(x, v, w, self.def.halo_nodes, |ci, xs, vs, ws| {
            let step = &step;
            dispatch(NodeChunk {
                step,
                ci,
                xs,
                vs,
                ws,
            })
        });
        self.finish_nodes(parts, clock, mass_scale)
    }

    /// The total mass and momentum scale of a whole, deformable contact body whose
    /// contact figures the node loop takes (`figures`); None otherwise. The scale
    /// needs the whole body's mass first (a sum in node order).
    fn mass_scale(&self, figures: bool) -> Option<(f64, f64)> {
        let taking = figures && self.def.contact && self.def.halo_nodes == 0;
        taking.then(|| {
            let m = self.total_mass();
            (m, Momentum::scale(m))
        })
    }

    /// The node chunks' results merged in chunk order, booked; the contact figures
    /// gathered where taken.
    fn finish_nodes(
        &mut self,
        parts: Vec<(NodeSums, Option<ChunkFigures>)>,
        clock: &StepClock,
        mass_scale: Option<(f64, f64)>,
    ) -> Result<(NodeSums, Option<NodeFigures>), Fault> {
        let (sums, figs): (Vec<NodeSums>, Vec<Option<ChunkFigures>>) = parts.into_iter().unzip();
        let total = NodeSums::total(&sums, clock.step, self.def.id)?;
        self.book(clock.h, &total);
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
