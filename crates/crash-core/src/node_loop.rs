//! The node loop of the integration stage (integrate.rs) for one chunk of `CHUNK`
//! nodes: gather each node's element force slots, advance it by central differences,
//! add its energy terms.
//!
//! Two choices make it cheaper without changing a bit:
//! - the slots are gathered for the whole chunk first, in a short loop of its own: the
//!   out-of-order core then overlaps the slot loads of many nodes, where inside the
//!   long update one node's gather chain was most of its time;
//! - it runs through `element::simd::dispatch`, so that it is compiled once per
//!   instruction-set path. It uses no lanes, but AVX2 and AVX-512 give it three-operand
//!   encodings (fewer register copies) and AVX-512 32 vector registers instead of 16
//!   (the baseline build spilled the gather's sums to the stack). The operations are the
//!   same IEEE operations in the same order and never a fused multiply-add
//!   (element::simd): the same bits on every path.
//!
//! Without Kelvin damping or contact forces the loop is instantiated without their
//! terms (const generics). The forces were skipped at run time before; the contact work
//! was added as zeros, which leaves its sum at +0.0 exactly as leaving it out does.

use crate::body::{BodyDef, NO_PROGRAM};
use crate::contact::figures::ChunkFigures;
use crate::element::real::Lanes;
use crate::element::simd::{prefetch, Lanewise};
use crate::element::Slot;
use crate::forces::CHUNK;
use crate::integrate::{NodeSums, StepClock};
use crate::Vec3;

/// How many nodes ahead the gather prefetches force slots.
const PREFETCH: usize = 8;

/// What every node chunk of one body's integration step reads.
#[derive(Clone, Copy)]
pub(crate) struct NodeStep<'a> {
    pub d: &'a BodyDef,
    /// The force slots and, with Kelvin damping, the Kelvin part of each (else empty).
    pub slots: &'a [Slot],
    pub kelvin: &'a [Slot],
    /// The forces carried as node sums (`summed`; empty: gather the slots).
    pub sums: &'a [Slot],
    /// Contact forces per node (empty: none this step).
    pub fc: &'a [Vec3],
    pub gravity: Vec3,
    pub t: f64,
    pub h: f64,
    pub hbar: f64,
    /// Mass damping c and the implicit factors 1 - c hbar / 2, 1 / (1 + c hbar / 2).
    pub c: f64,
    pub dn: f64,
    pub dd: f64,
    /// The momentum scale when the contact stage's figures are taken in the loop.
    pub scale: Option<f64>,
}

impl<'a> NodeStep<'a> {
    /// The step of `d` over `clock` from its force slots `slots` (with their Kelvin
    /// half, if any), or the node sums `sums` that carry them, and contact forces `fc`;
    /// `mass_scale` as `Body::mass_scale`.
    pub(crate) fn of(
        d: &'a BodyDef,
        (slots, sums): (&'a [Slot], &'a [Slot]),
        fc: &'a [Vec3],
        clock: &StepClock,
        gravity: Vec3,
        mass_scale: Option<(f64, f64)>,
    ) -> Self {
        let h = clock.h;
        let hbar = 0.5 * (clock.h_prev + h);
        let c = d.mass_damping;
        let (dn, dd) = (1.0 - 0.5 * c * hbar, 1.0 / (1.0 + 0.5 * c * hbar));
        // the force slots and, with Kelvin damping, the Kelvin part of each (empty
        // otherwise: an undamped body reads nothing more)
        let gn = d.gather_slot.len();
        let (slots, kelvin) = slots.split_at(gn);
        let kelvin = kelvin.get(..d.slot_count() - gn).unwrap_or_default();
        Self {
            d,
            slots,
            kelvin,
            sums,
            fc,
            gravity,
            t: clock.t,
            h,
            hbar,
            c,
            dn,
            dd,
            scale: mass_scale.map(|(_, sc)| sc),
        }
    }
}

/// One chunk of nodes of a step: chunk index `ci`, its positions and velocities.
pub(crate) struct NodeChunk<'s, 'a> {
    pub step: &'s NodeStep<'a>,
    pub ci: usize,
    pub xs: &'s mut [Vec3],
    pub vs: &'s mut [Vec3],
    pub ws: &'s mut [Vec3],
}

impl Lanewise for NodeChunk<'_, '_> {
    type Output = (NodeSums, Option<ChunkFigures>);

    #[inline(always)]
    fn run<S: Lanes>(self) -> Self::Output {
        match (self.step.kelvin.is_empty(), self.step.fc.is_empty()) {
            (true, true) => self.update::<false, false>(),
            (true, false) => self.update::<false, true>(),
            (false, true) => self.update::<true, false>(),
            (false, false) => self.update::<true, true>(),
        }
    }
}

impl NodeChunk<'_, '_> {
    #[inline(always)]
    fn update<const KELVIN: bool, const CONTACT: bool>(self) -> (NodeSums, Option<ChunkFigures>) {
        let NodeStep {
            d,
            slots,
            kelvin,
            sums,
            fc,
            gravity,
            t,
            h,
            hbar,
            c,
            dn,
            dd,
            scale,
        } = *self.step;
        let (xs, vs, ws) = (self.xs, self.vs, self.ws);
        let at = self.ci * CHUNK;
        let n = xs.len();
        // the slots' sums per node, or the sums the element stage carried (`summed`)
        let nn = d.x0.len();
        let collect = |out: &mut [[Vec3; 2]; CHUNK], slots: &[Slot], half: usize| {
            if sums.is_empty() {
                gather(out, slots, d, at, n)
            } else {
                let from = half * nn + at;
                for (o, q) in out.iter_mut().zip(&sums[from..from + n]) {
                    *o = [Vec3::new(q[0], q[1], q[2]), Vec3::new(q[3], q[4], q[5])];
                }
            }
        };
        let mut fim = [[Vec3::zeros(); 2]; CHUNK];
        collect(&mut fim, slots, 0);
        let fdm = KELVIN.then(|| {
            let mut fdm = [[Vec3::zeros(); 2]; CHUNK];
            collect(&mut fdm, kelvin, 1);
            fdm
        });
        let mut s = NodeSums::default();
        for k in 0..n {
            let i = at + k;
            let m = d.mass[i];
            let inr = d.inertia[i];
            // forces: external (gravity, loads), contact, minus internal
            let (mut f, mut mom) = d.external_at(i, gravity * m, t);
            let (fe, me) = (f, mom);
            let fcon = if CONTACT { fc[i] } else { Vec3::zeros() };
            if CONTACT {
                f += fcon;
            }
            let [fi, mi] = fim[k];
            f -= fi;
            mom -= mi;
            let v_old = vs[k];
            let w_old = ws[k];
            let mut v_new = (v_old * dn + f * (hbar / m)) * dd;
            let mut w_new = (w_old * dn + mom * (hbar / inr)) * dd;
            let free_v = v_new;
            let free_w = w_new;
            let fx = d.fixed[i];
            if fx != 0 {
                let (pv, pw) = match d.program[i] {
                    NO_PROGRAM => (Vec3::zeros(), Vec3::zeros()),
                    p => d.programs[p as usize].over_step(t, h, &d.curves),
                };
                for a in 0..3 {
                    if fx & (1 << a) != 0 {
                        v_new[a] = pv[a];
                    }
                    if fx & (8 << a) != 0 {
                        w_new[a] = pw[a];
                    }
                }
            }
            let vn = (v_old + v_new) * 0.5;
            let wn = (w_old + w_new) * 0.5;
            s.kinetic += 0.5 * (m * v_new.norm_squared() + inr * w_new.norm_squared());
            s.external += hbar * (fe.dot(&vn) + me.dot(&wn));
            if CONTACT {
                s.contact += hbar * fcon.dot(&vn);
            }
            s.internal_power += fi.dot(&v_new) + mi.dot(&w_new);
            if let Some(fdm) = &fdm {
                // the Kelvin force's work at the kinetic energy's time levels; the
                // shadow internal energy takes the elastic part only
                let [fd, md] = fdm[k];
                s.kelvin += hbar * (fd.dot(&vn) + md.dot(&wn));
                s.internal_power -= fd.dot(&v_new) + md.dot(&w_new);
            }
            if fx != 0 {
                // impulse the constraint applied, times the mean velocity; xs[k] is
                // still x_n, the position the reaction acts at
                let dv = (v_new - free_v, w_new - free_w);
                s.add_reaction((m, inr), dv, dd, (vn, wn), hbar, &xs[k]);
            }
            s.add_damping(c, hbar, (m, inr), (vn, wn));
            s.advance(i, h, (&mut xs[k], &mut vs[k], &mut ws[k]), v_new, w_new);
        }
        // the chunk is still in the cache: the contact stage's figures of it
        let fig = scale.map(|sc| ChunkFigures::of(s.lo, s.hi, vs, &d.mass[at..at + n], sc));
        (s, fig)
    }
}

/// The sums of the force slots (force, moment) of nodes `at..at + n` into `out`, each
/// node's slots in gather order (the additions of one node at a time, unchanged).
#[inline(always)]
fn gather(out: &mut [[Vec3; 2]; CHUNK], slots: &[Slot], d: &BodyDef, at: usize, n: usize) {
    let (gs, gi) = (&d.gather_start, &d.gather_slot);
    for (k, o) in out.iter_mut().enumerate().take(n) {
        let i = at + k;
        // the force slots of a node a few places ahead (see `prefetch`)
        if let Some(range) = gs.get(i + PREFETCH..i + PREFETCH + 2) {
            for &sl in &gi[range[0] as usize..range[1] as usize] {
                // a 48-byte slot starts at byte 0, 16, 32 or 48 of a line: it may end
                // on the next one
                let q = &slots[sl as usize];
                prefetch(&q[0]);
                prefetch(&q[5]);
            }
        }
        let mut f = Vec3::zeros();
        let mut m = Vec3::zeros();
        for &sl in &gi[gs[i] as usize..gs[i + 1] as usize] {
            let q = &slots[sl as usize];
            f += Vec3::new(q[0], q[1], q[2]);
            m += Vec3::new(q[3], q[4], q[5]);
        }
        *o = [f, m];
    }
}
