//! Domain decomposition of one body by elements (issue 16 point 2, first layer: in one
//! process). `bisect` cuts a body's elements into k parts of balanced cost by recursive
//! coordinate bisection of their centroids; `parts` builds from such a cut one sub-body
//! per part (owned nodes + a one-element halo) that steps bit-identically to the whole;
//! `contact` (second layer) steps a group of such split bodies in contact, each part
//! computing the hits on its owned nodes from a contact view of the whole group;
//! `shared` (the wiring) steps such a group with its parts spread over workers.

mod assemble;
mod closing;
mod contact;
mod export;
mod inner;
mod parts;
mod report;
mod select;
mod select_points;
mod shared;
mod view;

pub use closing::{PairSpeed, SplitFigures};
pub use contact::{GroupSplit, SplitError};
pub use parts::{Part, Split};
pub use shared::{merge_report, PartDt, PartState, SharedGroup};
pub use view::{View, ViewRule};

use crate::body::BodyDef;
use crate::error::CoreError;
use crate::Vec3;

/// Cost of one triangle per step, the unit of the element weights.
pub const TRI_COST: f64 = 1.0;
/// Cost of one quad per step relative to a triangle: the whole-step A/B of
/// docs/performance-history.md (second sitting of 2026-11-26, `shell_step` 1 thread): triangle
/// 6.97 / 6.12 ms for 100 352 elements, quad 13.14 / 11.39 ms for 100 489, i.e.
/// 69.5 / 61.0 and 130.8 / 113.3 ns per element-cycle: 1.88 and 1.86.
pub const QUAD_COST: f64 = 1.87;

/// Which part each element of a body belongs to: `part_of[e]` for the body's element
/// index e (triangles first, then quads, as in `BodyState::shell`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Partition {
    pub parts: usize,
    pub part_of: Vec<u32>,
}

impl Partition {
    /// Elements of part `p`, in element order.
    pub fn elements(&self, p: usize) -> Vec<usize> {
        (0..self.part_of.len())
            .filter(|&e| self.part_of[e] as usize == p)
            .collect()
    }

    /// The part owning each node of `def`: the part of its lowest-index element
    /// (u32::MAX for a node of no element). A part computes the elements of the nodes
    /// it owns (`Split::new`).
    pub fn owners(&self, def: &BodyDef) -> Vec<u32> {
        let mut owner = vec![u32::MAX; def.node_count()];
        for (e, &p) in self.part_of.iter().enumerate() {
            for &n in def.element_nodes(e) {
                if owner[n as usize] == u32::MAX {
                    owner[n as usize] = p;
                }
            }
        }
        owner
    }

    /// Summed weight of each part.
    pub fn weights(&self, weight: &[f64]) -> Vec<f64> {
        let mut w = vec![0.0; self.parts];
        for (e, &p) in self.part_of.iter().enumerate() {
            w[p as usize] += weight[e];
        }
        w
    }
}

/// Cost weight of every element of `def` (triangles then quads).
pub fn element_weights(def: &BodyDef) -> Vec<f64> {
    let mut w = vec![TRI_COST; def.tris.len()];
    w.resize(def.element_count(), QUAD_COST);
    w
}

/// Centroids of the elements of `def` at positions `x` (triangles then quads).
pub fn centroids(def: &BodyDef, x: &[Vec3]) -> Vec<Vec3> {
    let mean = |nodes: &[u32]| {
        nodes.iter().fold(Vec3::zeros(), |c, &n| c + x[n as usize]) / nodes.len() as f64
    };
    def.tris
        .iter()
        .map(|e| mean(&e.nodes))
        .chain(def.quads.iter().map(|e| mean(&e.nodes)))
        .collect()
}

/// Cost of integrating one owned node per step relative to a triangle's forces: the
/// showcase on one thread (`perf record -F 400 --call-graph dwarf target/release/crash
/// run scenes/sphere-on-plate.toml --threads 1 --end-time 1.2e-3`, session 33): the
/// node loop 759 samples over 13 963 nodes, the element kernels 1 053 over 27 212
/// triangle units (20 480 triangles, 3 600 quads): 0.054 against 0.039 a unit.
pub const NODE_COST: f64 = 1.4;

/// Rounds of `partition_body`'s balancing of what each part computes.
const BALANCE_ROUNDS: usize = 4;

/// Cut a body's elements into `k` parts by recursive coordinate bisection of their
/// centroids at its reference positions, weighted by `element_weights`, balanced by
/// what each part computes (`computed_costs`): a part holds its own elements and the
/// cut elements of the nodes it owns, which the parts on one side of a cut do not
/// (the showcase plate's left half held 60 quads and 61 nodes more than the right,
/// 3.3 %, and the holder of every body's part 0 did 1.75 % more work than the other).
/// Each round scales the parts' shares of the element weight by the mean computed cost
/// over theirs and cuts again, keeping the best cut (the most even computed costs,
/// the first of equals). Any cut gives the same bits; this one gives even work.
pub fn partition_body(def: &BodyDef, k: usize) -> Result<Partition, CoreError> {
    let err = |what| CoreError::Other {
        body: def.name.clone(),
        what,
    };
    let (c, w) = (centroids(def, &def.x0), element_weights(def));
    let mut shares = vec![1.0; k];
    let mut best = bisect_shares(&c, &w, &shares).map_err(err)?;
    let spread = |p: &Partition| {
        let cost = computed_costs(def, p, &w);
        let mean = cost.iter().sum::<f64>() / k as f64;
        let worst = cost.iter().fold(0.0, |m: f64, c| m.max((c - mean).abs()));
        (worst / mean, cost, mean)
    };
    let (mut best_spread, mut cost, mut mean) = spread(&best);
    for _ in 0..BALANCE_ROUNDS {
        if best_spread <= 1e-3 {
            break;
        }
        for (s, c) in shares.iter_mut().zip(&cost) {
            *s *= mean / c;
        }
        let next = bisect_shares(&c, &w, &shares).map_err(err)?;
        let (sp, nc, nm) = spread(&next);
        if sp < best_spread {
            (best, best_spread) = (next, sp);
        }
        (cost, mean) = (nc, nm);
    }
    Ok(best)
}

/// What each part of `part` computes a step: the weights of the elements it holds
/// (its own and every element at a node it owns; a node is owned by the part of its
/// lowest-index element: `Partition::owners`) and `NODE_COST` per owned node.
pub fn computed_costs(def: &BodyDef, part: &Partition, weight: &[f64]) -> Vec<f64> {
    let owner = part.owners(def);
    let mut cost = vec![0.0; part.parts];
    for &o in owner.iter().filter(|&&o| o != u32::MAX) {
        cost[o as usize] += NODE_COST;
    }
    let mut held: Vec<u32> = Vec::with_capacity(4);
    for (e, &w) in weight.iter().enumerate() {
        held.clear();
        held.push(part.part_of[e]);
        for &n in def.element_nodes(e) {
            let o = owner[n as usize];
            if !held.contains(&o) {
                held.push(o);
            }
        }
        for &p in &held {
            cost[p as usize] += w;
        }
    }
    cost
}

/// Recursive coordinate bisection of `points` with `weight`s into `k >= 1` parts: each
/// cut is normal to the longest side of the current set's bounding box and puts the
/// weight share k_left / k on the low side (k_left = k / 2, so any k, not only powers
/// of two). Points are ordered by coordinate, ties by index: the same input always
/// gives the same partition. Every part gets at least one point; error when k is 0 or
/// exceeds the number of points, or a weight is not finite and positive.
pub fn bisect(points: &[Vec3], weight: &[f64], k: usize) -> Result<Partition, String> {
    bisect_shares(points, weight, &vec![1.0; k])
}

/// `bisect` into `shares.len()` parts, part q taking the share `shares[q]` (relative,
/// finite and positive) of the weight: each cut puts on its low side the sum of its
/// low parts' shares over the sum of all of the set's.
pub fn bisect_shares(points: &[Vec3], weight: &[f64], shares: &[f64]) -> Result<Partition, String> {
    let (n, k) = (points.len(), shares.len());
    if k == 0 || k > n {
        return Err(format!("cannot cut {n} elements into {k} parts"));
    }
    if weight.len() != n || weight.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
        return Err("element weights must be finite and positive, one per element".into());
    }
    if shares.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return Err("part shares must be finite and positive".into());
    }
    let mut part_of = vec![0u32; n];
    let mut ids: Vec<usize> = (0..n).collect();
    cut(points, weight, shares, &mut ids, 0, &mut part_of);
    Ok(Partition { parts: k, part_of })
}

/// The axis of the longest side of a box of extent `ext`, ties to the lower axis (the
/// axis each cut of `bisect` is normal to).
pub fn longest_axis(ext: &Vec3) -> usize {
    (1..3).fold(0, |a, d| if ext[d] > ext[a] { d } else { a })
}

/// Assign `ids` to parts `first..first + shares.len()`.
fn cut(
    points: &[Vec3],
    weight: &[f64],
    shares: &[f64],
    ids: &mut [usize],
    first: u32,
    out: &mut [u32],
) {
    let k = shares.len();
    if k == 1 {
        for &e in ids.iter() {
            out[e] = first;
        }
        return;
    }
    let (mut lo, mut hi) = (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
    for &e in ids.iter() {
        lo = lo.inf(&points[e]);
        hi = hi.sup(&points[e]);
    }
    let axis = longest_axis(&(hi - lo));
    ids.sort_unstable_by(|&a, &b| points[a][axis].total_cmp(&points[b][axis]).then(a.cmp(&b)));
    let kl = k / 2;
    let total: f64 = ids.iter().map(|&e| weight[e]).sum();
    let low: f64 = shares[..kl].iter().sum();
    let target = total * low / (low + shares[kl..].iter().sum::<f64>());
    // the prefix whose weight is nearest the target, leaving each side a point per part
    let (mut best, mut best_err, mut acc) = (kl, f64::INFINITY, 0.0);
    for (m, &e) in ids.iter().enumerate() {
        acc += weight[e];
        let len = m + 1;
        if len < kl || ids.len() - len < k - kl {
            continue;
        }
        let err = (acc - target).abs();
        if err < best_err {
            (best, best_err) = (len, err);
        }
        if acc > target {
            break;
        }
    }
    let (left, right) = ids.split_at_mut(best);
    cut(points, weight, &shares[..kl], left, first, out);
    cut(points, weight, &shares[kl..], right, first + kl as u32, out);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(nx: usize, ny: usize) -> Vec<Vec3> {
        (0..ny)
            .flat_map(|j| (0..nx).map(move |i| Vec3::new(i as f64, j as f64, 0.0)))
            .collect()
    }

    #[test]
    fn every_point_is_in_exactly_one_part_and_no_part_is_empty() {
        let p = grid(13, 7);
        let w = vec![1.0; p.len()];
        for k in 1..=9 {
            let part = bisect(&p, &w, k).expect("valid");
            assert!(part.part_of.iter().all(|&q| (q as usize) < k));
            for q in 0..k {
                assert!(!part.elements(q).is_empty(), "k = {k}: part {q} empty");
            }
        }
    }

    #[test]
    fn k_of_zero_or_above_the_element_count_is_refused() {
        let p = grid(2, 2);
        let w = vec![1.0; 4];
        assert!(bisect(&p, &w, 0).is_err());
        assert!(bisect(&p, &w, 5).is_err());
        assert!(bisect(&p, &w, 4).is_ok());
        assert!(bisect(&p, &[1.0, 1.0, f64::NAN, 1.0], 2).is_err());
    }
}
