//! Fast motion: the closing-speed time step limit of a candidate pair and the swept
//! crossing check (docs/theory-contact.md, "Fast motion").
//!
//! *Closing speed.* For a pair (a, b) the speed of any node of a relative to any point
//! of b is at most `max_i |v_i - u| + max_j |v_j - u|` for any common velocity u; crash
//! takes the smaller of the bounds with u = the centre-of-mass velocity of a and of b.
//! Under `SpeedRule::LimitDt` the pair's step is limited to
//! `CLOSING_FRACTION * c / v_close`, c = (t_a + t_b)/2.
//!
//! *Crossing.* A node crossed a segment in the step x_n -> x_{n+1} if its signed
//! distance to the plane of a (sub-)triangle of the segment changed sign and, at the
//! time where the linearly interpolated distance vanishes, the node lies within
//! `CROSSING_TOLERANCE * c` of that (sub-)triangle. x_n is recovered as
//! x_{n+1} - h v_{n+1/2} (the positions the step moved from, to round-off): the check is
//! a function of the state after the step only.

use super::figures::NodeFigures;
use super::segment::{triangle_weights, Segment};
use super::speeds::SpeedBoxes;
use super::surface::{NodeChunk, Surface, NODE_CHUNK};
use super::verlet::{candidates, NodeLists};
use crate::body::Body;
use crate::Vec3;
use rayon::prelude::*;

/// Largest distance of the node to the crossed (sub-)triangle at the crossing time, as
/// a fraction of the contact distance c. A node that goes round the rounded edge of a
/// slab at contact distance stays about c from the edge; one that goes through the
/// mid-surface is at 0 (up to the rotation of the facet within the step).
pub const CROSSING_TOLERANCE: f64 = 0.25;

/// A body's momentum on a fixed quantum: each node's m v, its components clamped to
/// `SPEED_CAP` and scaled by `Momentum::scale` of the whole body's mass, truncated to
/// an integer. Integer addition is associative, so sums over parts merged in any order
/// (a body split over workers) give the bits of the sum over the whole body: the mean
/// velocity the closing speed reads is then the same in every mode without a gather of
/// every node's velocity (docs/architecture-cluster.md, "The closing speed").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Momentum(pub [i64; 3]);

/// Largest speed component a node's momentum term keeps [m/s] (2^20, about 1e6: far
/// beyond any impact a shell survives); with the scale below no sum can overflow.
pub const SPEED_CAP: f64 = 1_048_576.0;

/// Bits of headroom between a body's largest momentum sum and i64's range.
const SCALE_BITS: i32 = 41;

impl Momentum {
    /// The scale of a body of total mass `mass`: 2^(41 - E) with mass < 2^E, a power of
    /// two (so scaling is exact). Every term is at most m_i 2^20 2^(41-E), and their
    /// sum at most mass 2^(61-E) < 2^61. The quantum of the mean velocity is then
    /// 2^(E-41) / mass <= 2^-40 m/s per node: the bound below holds for any common
    /// velocity, so only its determinism matters.
    pub fn scale(mass: f64) -> f64 {
        if !(mass.is_finite() && mass > 0.0) {
            return 0.0;
        }
        let e = ((mass.to_bits() >> 52) & 0x7ff) as i32 - 1022;
        2f64.powi(SCALE_BITS - e)
    }

    /// The sum over nodes (`v[k]`, `m[k]`) with the body's scale: chunks on the pool
    /// (integer sums: any grouping gives the same bits; a serial pass over the
    /// showcase's sphere was a tenth of its contact stage and held one thread of two).
    pub fn of(v: &[Vec3], m: &[f64], scale: f64) -> Self {
        v.par_chunks(super::stage::PAR_CHUNK)
            .zip(m.par_chunks(super::stage::PAR_CHUNK))
            .map(|(v, m)| Self::of_serial(v, m, scale))
            .reduce(Self::default, |a, b| a + b)
    }

    pub(crate) fn of_serial(v: &[Vec3], m: &[f64], scale: f64) -> Self {
        let mut p = [0i64; 3];
        for (v, &mi) in v.iter().zip(m) {
            for d in 0..3 {
                p[d] = p[d].wrapping_add(Self::term(mi, v[d], scale));
            }
        }
        Self(p)
    }

    /// One node's term of one component: m v on the quantum.
    #[inline]
    pub(crate) fn term(m: f64, v: f64, scale: f64) -> i64 {
        // NaN clamps to NaN and truncates to 0: a NaN state faults elsewhere
        (m * v.clamp(-SPEED_CAP, SPEED_CAP) * scale) as i64
    }

    /// The mean velocity of a body of total mass `mass` and scale `scale` whose
    /// momentum this is.
    pub fn mean(self, mass: f64, scale: f64) -> Vec3 {
        if scale > 0.0 {
            Vec3::new(self.0[0] as f64, self.0[1] as f64, self.0[2] as f64) / (scale * mass)
        } else {
            Vec3::zeros()
        }
    }
}

/// The sum of two (any order, any grouping: the same bits).
impl std::ops::Add for Momentum {
    type Output = Momentum;
    fn add(self, o: Self) -> Self {
        Self(std::array::from_fn(|d| self.0[d].wrapping_add(o.0[d])))
    }
}

/// Centre-of-mass velocity of a body (mass-weighted mean of v, summed on the fixed
/// quantum of `Momentum`).
pub fn mean_velocity(b: &Body) -> Vec3 {
    let mass = b.total_mass();
    let scale = Momentum::scale(mass);
    Momentum::of(&b.state.v, &b.def.mass, scale).mean(mass, scale)
}

/// What the closing speed needs of one body, taken once per contact pass however many
/// pairs it is in: its mean velocity and, for a kinematic body whose nodes move with
/// one velocity per program (they do: the integration gives every node its program's
/// value; checked here, a state that does not fit takes the node loop), those
/// velocities: the maxima over the nodes are then maxima over a few values.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BodySpeed {
    pub mean: Vec3,
    /// The largest |v - mean| over the nodes: one figure for all of the body's pairs.
    own: f64,
    /// The distinct velocities of the nodes (one per program, and rest), if known.
    uniform: Option<Vec<Vec3>>,
    /// Otherwise the velocity boxes of the node chunks (a body in many pairs).
    boxes: SpeedBoxes,
}

impl BodySpeed {
    pub fn of(b: &Body) -> Self {
        Self::of_given(b, None)
    }

    /// `of`, with the figures the integration took of this body's nodes when it has
    /// them (the same bits, without reading the nodes again).
    pub fn of_given(b: &Body, given: Option<&NodeFigures>) -> Self {
        let uniform = if b.def.kinematic {
            program_velocities(b)
        } else {
            None
        };
        let (mean, boxes) = match (given, &uniform) {
            (Some(f), None) => (f.mean(), f.speeds.clone()),
            (_, None) => (mean_velocity(b), SpeedBoxes::of(&b.state.v)),
            (_, Some(_)) => (mean_velocity(b), SpeedBoxes::default()),
        };
        let mut speed = Self {
            mean,
            own: 0.0,
            uniform,
            boxes,
        };
        speed.own = max_speed_rel(b, &speed, &speed.mean);
        speed
    }
}

/// The velocity of each program's nodes (nodes without one last) when all nodes of a
/// program have the same velocity, else None (one serial read of v: comparisons only).
fn program_velocities(b: &Body) -> Option<Vec<Vec3>> {
    let d = &*b.def;
    let rest = d.programs.len();
    let mut seen: Vec<Option<Vec3>> = vec![None; rest + 1];
    for (v, &p) in b.state.v.iter().zip(&d.program) {
        let c = if p == crate::body::NO_PROGRAM {
            rest
        } else {
            p as usize
        };
        match seen.get_mut(c)? {
            Some(r) if r != v => return None,
            Some(_) => {}
            slot => *slot = Some(*v),
        }
    }
    Some(seen.into_iter().flatten().collect())
}

/// Largest |v - u| over the nodes (a maximum: the same bits in any order); over the
/// distinct velocities when they are known (the same maximum: equal velocities give
/// equal norms, +0 and -0 alike), else through the chunks' velocity boxes.
fn max_speed_rel(b: &Body, speed: &BodySpeed, u: &Vec3) -> f64 {
    if let Some(vs) = &speed.uniform {
        return vs.iter().fold(0.0, |m: f64, v| m.max((v - u).norm()));
    }
    speed.boxes.max_speed(&b.state.v, u)
}

/// The four maxima a pair's closing speed reads: the largest |v - u_a| and |v - u_b|
/// over the nodes of `a`, then over those of `b` (u: the bodies' mean velocities; each
/// body's speed relative to its own mean is computed once, in `BodySpeed::of`).
/// Maxima of maxima over any split of the nodes give the same bits.
pub fn speed_maxima(a: &Body, b: &Body, sa: &BodySpeed, sb: &BodySpeed) -> [f64; 4] {
    let (ua, ub) = (sa.mean, sb.mean);
    [
        sa.own,
        max_speed_rel(a, sa, &ub),
        max_speed_rel(b, sb, &ua),
        sb.own,
    ]
}

/// The closing speed from the four maxima of `speed_maxima`: the smaller of the bounds
/// with u = u_a and u = u_b.
pub fn closing_of(m: [f64; 4]) -> f64 {
    let with_a = m[0] + m[2];
    let with_b = m[1] + m[3];
    with_a.min(with_b)
}

/// Upper bound of the speed of any node of `a` relative to any point of `b` [m/s].
/// `sa`, `sb`: their `BodySpeed` (a body in many pairs takes it once per pass).
pub fn closing_speed(a: &Body, b: &Body, sa: &BodySpeed, sb: &BodySpeed) -> f64 {
    closing_of(speed_maxima(a, b, sa, sb))
}

/// A node that crossed a segment's mid-surface in the step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    pub node: usize,
    pub segment: usize,
    /// |normal relative speed| of the node and the crossed point [m/s].
    pub closing_speed: f64,
}

/// Signed distance of p to the plane of (a, b, c) and the unit normal (None if the
/// triangle is degenerate).
fn plane(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> Option<(f64, Vec3)> {
    let n = (b - a).cross(&(c - a));
    let l = n.norm();
    (l > 0.0).then(|| {
        let n = n / l;
        ((p - a).dot(&n), n)
    })
}

/// The crossing of one (sub-)triangle, given its corners before (`t0`) and after (`t1`)
/// the step and the node before and after; returns the crossing time fraction.
fn crosses(p0: &Vec3, p1: &Vec3, t0: &[Vec3; 3], t1: &[Vec3; 3], c: f64) -> Option<f64> {
    let (d0, _) = plane(p0, &t0[0], &t0[1], &t0[2])?;
    let (d1, _) = plane(p1, &t1[0], &t1[1], &t1[2])?;
    let flipped = (d0 > 0.0 && d1 <= 0.0) || (d0 < 0.0 && d1 >= 0.0);
    if !flipped {
        return None;
    }
    let tau = d0 / (d0 - d1);
    let at = |x0: &Vec3, x1: &Vec3| x0 + (x1 - x0) * tau;
    let p = at(p0, p1);
    let (a, b, cc) = (at(&t0[0], &t1[0]), at(&t0[1], &t1[1]), at(&t0[2], &t1[2]));
    let w = triangle_weights(&p, &a, &b, &cc);
    let q = a * w[0] + b * w[1] + cc * w[2];
    ((p - q).norm() <= CROSSING_TOLERANCE * c).then_some(tau)
}

/// The (sub-)triangles of a segment with their corner weights: a triangle is itself;
/// a quad is split into four around its centroid, as in the projection.
fn sub_triangles(seg: &Segment, x: &[Vec3]) -> ([[Vec3; 3]; 4], [[f64; 4]; 12], usize) {
    sub_triangles_at(seg, |n| x[n as usize])
}

/// `sub_triangles` with the nodes' positions given by `at` (node id -> position).
fn sub_triangles_at(
    seg: &Segment,
    at: impl Fn(u32) -> Vec3,
) -> ([[Vec3; 3]; 4], [[f64; 4]; 12], usize) {
    let xs = seg.nodes.map(at);
    let mut tris = [[Vec3::zeros(); 3]; 4];
    // weights of each corner on the segment's nodes (corner k of triangle j: row 3j+k)
    let mut w = [[0.0; 4]; 12];
    if seg.count == 3 {
        tris[0] = [xs[0], xs[1], xs[2]];
        w[0][0] = 1.0;
        w[1][1] = 1.0;
        w[2][2] = 1.0;
        return (tris, w, 1);
    }
    let c = (xs[0] + xs[1] + xs[2] + xs[3]) * 0.25;
    for k in 0..4 {
        tris[k] = [c, xs[k], xs[(k + 1) % 4]];
        w[3 * k] = [0.25; 4];
        w[3 * k + 1][k] = 1.0;
        w[3 * k + 2][(k + 1) % 4] = 1.0;
    }
    (tris, w, 4)
}

/// The first node of `nb` (in node order) that crossed a segment of `sb` in the step of
/// length h, with the segment it crossed (lowest index among those it crossed).
/// `self_pass`: the same body; segments excluded from self-contact are not checked.
pub fn first_crossing(
    nb: &Body,
    chunks: &[NodeChunk],
    sb: &Body,
    surf: &Surface,
    self_pass: bool,
    h: f64,
    lists: &mut NodeLists,
) -> Option<Crossing> {
    if h <= 0.0 {
        return None;
    }
    let c = 0.5 * (nb.def.section.thickness + sb.def.section.thickness);
    // the search's query half-size (narrow::search): the lists serve both
    let reach = 0.5 * nb.def.section.thickness;
    let xb1 = &sb.state.x;
    // positions before the step, of the corners a candidate needs only
    let before = |n: u32| xb1[n as usize] - sb.state.v[n as usize] * h;
    // max |v| h = (max |v|) h exactly: rounding x -> x h is monotone for h > 0
    let seg_move = surf.chunks.iter().map(|k| k.vmax).fold(0.0, f64::max) * h;
    let (lo, hi) = super::narrow::reach_box(surf, sb, nb);
    // each node's reach below is at most the chunk's: skip what none can meet
    let live = lists.live_chunks(&nb.state.x, NODE_CHUNK, |ci| {
        chunks
            .get(ci)
            .is_none_or(|k| k.meets(&lo, &hi, k.vmax * h + seg_move))
    });
    let chunks: Vec<Option<Crossing>> = live
        .into_par_iter()
        // single chunks: the few near the other body hold all the work (forces.rs)
        .with_max_len(1)
        .map(|(ci, xs, lists)| {
            let mut cand = Vec::new();
            for (k, p1) in xs.iter().enumerate() {
                let i = ci * NODE_CHUNK + k;
                let v = nb.state.v[i];
                let p0 = p1 - v * h;
                let r = v.norm() * h + seg_move;
                let grown = |d: usize| p1[d] >= lo[d] - r && p1[d] <= hi[d] + r;
                if !(0..3).all(grown) {
                    continue;
                }
                candidates(&mut lists[k], surf, p1, r, reach, &mut cand);
                cand.sort_unstable();
                for &j in &cand {
                    if self_pass && surf.near_in_topology(i as u32, j) {
                        continue;
                    }
                    let seg = &surf.segments[j as usize];
                    let (t1, w, n) = sub_triangles(seg, xb1);
                    let (t0, _, _) = sub_triangles_at(seg, before);
                    for s in 0..n {
                        let Some(tau) = crosses(&p0, p1, &t0[s], &t1[s], c) else {
                            continue;
                        };
                        if self_pass {
                            let x0 = &nb.def.x0;
                            let pr = super::segment::project(&x0[i], seg, &sb.def.x0);
                            if pr.dist < c {
                                continue;
                            }
                        }
                        // relative velocity of the node and the crossed point
                        let pt = p0 + (p1 - p0) * tau;
                        let corners: Vec<Vec3> = (0..3)
                            .map(|q| t0[s][q] + (t1[s][q] - t0[s][q]) * tau)
                            .collect();
                        let bw = triangle_weights(&pt, &corners[0], &corners[1], &corners[2]);
                        let mut vs = Vec3::zeros();
                        for q in 0..3 {
                            for (m, &nd) in seg.nodes().iter().enumerate() {
                                vs += sb.state.v[nd as usize] * (bw[q] * w[3 * s + q][m]);
                            }
                        }
                        let normal = (corners[1] - corners[0]).cross(&(corners[2] - corners[0]));
                        let l = normal.norm();
                        let rel = v - vs;
                        let closing = if l > 0.0 {
                            (rel.dot(&normal) / l).abs()
                        } else {
                            rel.norm()
                        };
                        return Some(Crossing {
                            node: i,
                            segment: j as usize,
                            closing_speed: closing,
                        });
                    }
                }
            }
            None
        })
        .collect();
    chunks.into_iter().flatten().next()
}
