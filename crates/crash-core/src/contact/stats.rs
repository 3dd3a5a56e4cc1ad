//! Per-pair contact statistics of a force pass (contacts.csv, rcforc) and the loads
//! a pass puts on kinematic bodies (their work in the energy ledger).
//!
//! The force sums are exact integer sums on a fixed quantum (`Tally`), so that a pair
//! whose pushes are computed in pieces (a group split over workers: each holder books
//! the pushes of the slave nodes it owns) gives the bits of one process in any order.

use crate::body::NO_PROGRAM;
use crate::Vec3;
use serde::{Deserialize, Serialize};

/// Bits below the newton in a `Tally` term: a quantum of 2^-64 N (5e-20 N), far below
/// any push a shell feels.
const QUANTUM_BITS: i32 = 64;

/// Largest force magnitude a term keeps [N] (2^62: no physical push comes near; with
/// the quantum above a term uses 126 bits of an i128).
const FORCE_CAP: f64 = 4.611_686_018_427_388e18;

/// Sums of push forces of a pair as integers on the quantum 2^-64 N: the normal force
/// magnitudes and the force on body a. Integer addition is associative, so any
/// grouping of the pushes gives the same sums (a float sum would depend on the order).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tally {
    pub normal: i128,
    pub on_a: [i128; 3],
}

impl Tally {
    /// A force on the quantum (truncated toward zero; NaN counts 0: a non-finite
    /// state stops the run elsewhere).
    fn fixed(f: f64) -> i128 {
        (f.clamp(-FORCE_CAP, FORCE_CAP) * 2f64.powi(QUANTUM_BITS)) as i128
    }

    /// A sum back in newtons (rounded to the nearest double).
    pub fn value(s: i128) -> f64 {
        s as f64 * 2f64.powi(-QUANTUM_BITS)
    }

    pub(crate) fn push(&mut self, normal: f64, on_a: Option<Vec3>) {
        self.normal = self.normal.wrapping_add(Self::fixed(normal));
        if let Some(f) = on_a {
            for d in 0..3 {
                self.on_a[d] = self.on_a[d].wrapping_add(Self::fixed(f[d]));
            }
        }
    }

    pub fn add(&self, o: &Tally) -> Tally {
        Tally {
            normal: self.normal.wrapping_add(o.normal),
            on_a: std::array::from_fn(|d| self.on_a[d].wrapping_add(o.on_a[d])),
        }
    }
}

/// What a pair's forces from one pass do to a kinematic body over the next step, kept
/// so that its work can be counted by the integration's own rule once that step's
/// length is known: W = hbar f_n . (v_{n-1/2} + v_{n+1/2}) / 2 summed over the nodes,
/// where v_{n+1/2} is the prescribed velocity (every DOF of a kinematic body is).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct KinLoad {
    /// Sum over the pushes of f . v, v the node's velocity at the pass [W].
    pub power: f64,
    /// Force summed per velocity program of the pushed nodes, sorted by program; nodes
    /// held at rest (no program) are left out [N].
    pub by_program: Vec<(u16, Vec3)>,
    /// The force per node, sorted by node, each summed in hit order [N]: what an output
    /// frame shows on the kinematic body (the master sums the pairs in pair order);
    /// workers send it only before a frame (empty otherwise).
    #[serde(default)]
    pub nodes: Vec<(u32, Vec3)>,
}

impl KinLoad {
    pub(crate) fn push(&mut self, node: u32, f: Vec3, v: Vec3, program: u16) {
        self.nodes.push((node, f));
        self.power += f.dot(&v);
        if program == NO_PROGRAM {
            return;
        }
        match self.by_program.binary_search_by_key(&program, |p| p.0) {
            Ok(k) => self.by_program[k].1 += f,
            Err(k) => self.by_program.insert(k, (program, f)),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.power == 0.0 && self.by_program.is_empty() && self.nodes.is_empty()
    }

    /// A copy with or without the per-node forces (sent only before a frame).
    fn copy(&self, nodes: bool) -> Self {
        Self {
            power: self.power,
            by_program: self.by_program.clone(),
            nodes: if nodes {
                self.nodes.clone()
            } else {
                Vec::new()
            },
        }
    }

    /// Sum the pushes per node (kept in hit order by the stable sort).
    pub(crate) fn settle_nodes(&mut self) {
        if self.nodes.is_empty() {
            return;
        }
        self.nodes.sort_by_key(|n| n.0);
        let mut out: Vec<(u32, Vec3)> = Vec::with_capacity(self.nodes.len());
        for &(n, f) in &self.nodes {
            match out.last_mut() {
                Some(last) if last.0 == n => last.1 += f,
                _ => out.push((n, f)),
            }
        }
        self.nodes = out;
    }
}

/// Contact statistics of one candidate body pair after a force pass.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairStats {
    /// Body ids, a <= b (a == b: self-contact).
    pub a: u32,
    pub b: u32,
    /// Nodes (of either body) pushed by a penalty force.
    pub active_nodes: usize,
    /// Largest penetration depth [m] and its ratio to the thinner body's thickness.
    pub max_penetration: f64,
    pub max_penetration_ratio: f64,
    /// Sum of the normal force magnitudes [N].
    pub normal_force: f64,
    /// Resultant contact force on body a from body b [N].
    pub force_on_a: Vec3,
    /// The exact sums behind `normal_force` and `force_on_a` (`Tally`): shares of the
    /// pair's pushes computed apart (a split group's holders) add to the same bits.
    #[serde(default)]
    pub tally: Tally,
    /// This pass's forces on body a (on body b) when it is kinematic (empty otherwise),
    /// whose own motion never feels contact: per pair, so that the energy ledger
    /// (`KinematicWork`) counts their work in pair order whatever the grouping.
    #[serde(default)]
    pub kin_a: KinLoad,
    #[serde(default)]
    pub kin_b: KinLoad,
}

impl PairStats {
    /// The statistics of pair (a, b) before any push is booked.
    pub(crate) fn empty(a: u32, b: u32, active_nodes: usize) -> Self {
        Self {
            a,
            b,
            active_nodes,
            max_penetration: 0.0,
            max_penetration_ratio: 0.0,
            normal_force: 0.0,
            force_on_a: Vec3::zeros(),
            tally: Tally::default(),
            kin_a: KinLoad::default(),
            kin_b: KinLoad::default(),
        }
    }

    /// Book one push: its normal force magnitude, and its force on body a (None for a
    /// self pair, which has no resultant).
    pub(crate) fn book(&mut self, depth: f64, normal_force: f64, on_a: Option<Vec3>) {
        self.max_penetration = self.max_penetration.max(depth);
        self.tally.push(normal_force, on_a);
    }

    /// The figures from the sums once every push is booked (`thin`: the thinner body's
    /// thickness).
    pub(crate) fn settle(&mut self, thin: f64) {
        self.values_from_tally();
        self.max_penetration_ratio = self.max_penetration / thin;
    }

    fn values_from_tally(&mut self) {
        self.normal_force = Tally::value(self.tally.normal);
        self.force_on_a = Vec3::from_fn(|d, _| Tally::value(self.tally.on_a[d]));
    }

    /// Join another share of the same pair's pushes (a split group's holders each
    /// book the pushes of the slave nodes they own): counts and sums add, maxima
    /// stay maxima, so the result is the whole pair's in any order. Loads on kinematic
    /// bodies are not merged: a split group holds none.
    pub fn merge(&mut self, o: &PairStats) {
        debug_assert_eq!((self.a, self.b), (o.a, o.b));
        self.active_nodes += o.active_nodes;
        self.max_penetration = self.max_penetration.max(o.max_penetration);
        // the ratio of the max (division is monotone: the max of the ratios)
        self.max_penetration_ratio = self.max_penetration_ratio.max(o.max_penetration_ratio);
        self.tally = self.tally.add(&o.tally);
        self.values_from_tally();
    }

    /// Merge shares (`add`, sorted by pair) into `into` (sorted by pair): a pair in
    /// both is merged, a new one inserted in its place.
    pub fn merge_sorted(into: &mut Vec<PairStats>, add: &[PairStats]) {
        for s in add {
            match into.binary_search_by_key(&(s.a, s.b), |x| (x.a, x.b)) {
                Ok(k) => into[k].merge(s),
                Err(k) => into.insert(k, s.clone()),
            }
        }
    }

    /// A copy for a step report: the per-node loads on kinematic bodies only when
    /// `nodes` (a frame follows), so other steps neither copy nor send them.
    pub fn for_report(&self, nodes: bool) -> Self {
        Self {
            kin_a: self.kin_a.copy(nodes),
            kin_b: self.kin_b.copy(nodes),
            ..*self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tally_sums_are_the_same_bits_in_any_order() {
        let f: [f64; 6] = [1.0e-3, 2.5e4, -7.1e2, 3.3e-9, 1.0 / 3.0, -2.0e-12];
        let mut fwd = Tally::default();
        for x in f {
            fwd.push(x.abs(), Some(Vec3::new(x, -x, 0.5 * x)));
        }
        let (mut p, mut q) = (Tally::default(), Tally::default());
        for (k, x) in f.iter().rev().enumerate() {
            let t = if k % 2 == 0 { &mut p } else { &mut q };
            t.push(x.abs(), Some(Vec3::new(*x, -x, 0.5 * x)));
        }
        assert_eq!(fwd, q.add(&p));
        // within a quantum per term of the float sum
        let float: f64 = f.iter().map(|x| x.abs()).sum();
        assert!((Tally::value(fwd.normal) - float).abs() < 1e-12 * float);
    }
}
