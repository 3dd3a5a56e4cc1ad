//! Narrow phase of one pass: the nodes of one body against the segments of another (or
//! of itself). Each node takes the closest segment (ties: lowest segment index), so the
//! outcome depends only on exact geometry, never on the tree or on thread count.
//! Gap with shell thickness: g = d - (t_node + t_segment) / 2, d the distance of the node
//! to the segment's mid-surface.

use super::config::{ContactConfig, PenaltyKind};
use super::segment::{project, Projection};
use super::smooth::smoothed;
use super::surface::{NodeChunk, Surface, NODE_CHUNK};
use super::verlet::{candidates, NodeLists};
use crate::body::Body;
use crate::Vec3;
use rayon::prelude::*;

/// Distances within this fraction of the contact distance of the closest one are a tie,
/// won by the lowest segment index.
pub const TIE: f64 = 1e-9;

/// A node within contact distance of a segment.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    pub node: u32,
    pub segment: u32,
    pub proj: Projection,
    /// Penetration depth (t_a + t_b)/2 - d > 0.
    pub depth: f64,
}

/// Box (lo, hi) beyond which a node cannot touch the segment body: its node box
/// (`surf.bounds()`, fresh) grown by both half-thicknesses.
pub fn reach_box(surf: &Surface, seg_body: &Body, node_body: &Body) -> (Vec3, Vec3) {
    let (lo, hi) = surf.bounds();
    let c = 0.5 * (seg_body.def.section.thickness + node_body.def.section.thickness);
    (lo.add_scalar(-c), hi.add_scalar(c))
}

/// Distance from p to the axis-aligned box of the given nodes (0 inside).
fn box_distance(p: &Vec3, nodes: &[u32], x: &[Vec3]) -> f64 {
    let mut lo = x[nodes[0] as usize];
    let mut hi = lo;
    for &n in &nodes[1..] {
        lo = lo.inf(&x[n as usize]);
        hi = hi.sup(&x[n as usize]);
    }
    let d = (lo - p).sup(&Vec3::zeros()) + (p - hi).sup(&Vec3::zeros());
    d.norm()
}

/// All nodes of `nb` penetrating the surface of `sb` (`surf` its search data, fresh).
/// `self_pass`: nb and sb are the same body; segments holding the node or a neighbour,
/// and segments already within contact distance in the reference configuration, are
/// excluded. `chunks`: `node_chunks(nb)` at this pass (chunks out of reach are skipped).
/// `lists`: the pass's node lists (`verlet.rs`; any lists of this pass, or new ones).
pub fn search(
    nb: &Body,
    chunks: &[NodeChunk],
    sb: &Body,
    surf: &Surface,
    self_pass: bool,
    lists: &mut NodeLists,
) -> Vec<Hit> {
    let c = 0.5 * (nb.def.section.thickness + sb.def.section.thickness);
    let r = 0.5 * nb.def.section.thickness;
    let tie = TIE * c;
    let (lo, hi) = reach_box(surf, sb, nb);
    let inside = |p: &Vec3| (0..3).all(|d| p[d] >= lo[d] && p[d] <= hi[d]);
    // only the chunks whose box meets the reach go to the pool (`live_chunks`)
    let live = lists.live_chunks(&nb.state.x, NODE_CHUNK, |ci| {
        chunks.get(ci).is_none_or(|k| k.meets(&lo, &hi, 0.0))
    });
    let chunks: Vec<Vec<Hit>> = live
        .into_par_iter()
        // single chunks: the few near the other body hold all the work (forces.rs)
        .with_max_len(1)
        .map(|(ci, xs, lists)| {
            let mut out = Vec::new();
            let mut cand = Vec::new();
            let mut close: Vec<(Projection, u32)> = Vec::new();
            for (k, p) in xs.iter().enumerate() {
                if !inside(p) {
                    continue;
                }
                let i = (ci * NODE_CHUNK + k) as u32;
                candidates(&mut lists[k], surf, p, r, r, &mut cand);
                // every candidate within the tie tolerance of the closest one, then the
                // lowest index among them: a function of the geometry, not of the
                // candidates' order, and the same for distances equal up to round-off
                // (a node over the shared edge of two segments)
                close.clear();
                let mut dmin = f64::INFINITY;
                for &j in &cand {
                    if self_pass && surf.near_in_topology(i, j) {
                        continue;
                    }
                    let seg = &surf.segments[j as usize];
                    // cheap lower bound: distance to the segment's node box; skipping
                    // only candidates beyond the tolerance keeps the choice
                    let lb = box_distance(p, seg.nodes(), &sb.state.x);
                    if lb >= c || lb > dmin + tie {
                        continue;
                    }
                    let pr = project(p, seg, &sb.state.x);
                    if pr.dist.is_nan() {
                        continue;
                    }
                    dmin = dmin.min(pr.dist);
                    close.push((pr, j));
                }
                let best = close
                    .iter()
                    .filter(|(pr, _)| pr.dist <= dmin + tie)
                    .min_by_key(|(_, j)| *j)
                    .copied();
                let Some((proj, j)) = best else { continue };
                if proj.dist.is_nan() || proj.dist >= c {
                    continue;
                }
                if self_pass {
                    // already this close at the start: part of the shape, not a contact
                    let seg = &surf.segments[j as usize];
                    if project(&nb.def.x0[i as usize], seg, &sb.def.x0).dist < c {
                        continue;
                    }
                }
                out.push(Hit {
                    node: i,
                    segment: j,
                    proj,
                    depth: c - proj.dist,
                });
            }
            out
        })
        .collect();
    chunks.into_iter().flatten().collect()
}

/// Nodal normals of a pass: of the segment body and of the node body.
#[derive(Debug, Clone, Copy)]
pub struct Normals<'a> {
    pub segment: &'a [Vec3],
    pub node: &'a [Vec3],
}

/// The penalty force of a hit, acting on the node (the segment nodes get minus it times
/// their weights).
#[derive(Debug, Clone, Copy)]
pub struct Push {
    pub hit: Hit,
    pub force: Vec3,
    pub normal_force: f64,
    /// Weights of the point where the reaction acts on the segment's nodes (sum 1).
    pub weights: [f64; 4],
}

/// Unit normal pointing from the segment to the node: the direction to the node, or
/// the face normal on the node's side when the node sits on the mid-surface.
fn normal(p: &Vec3, pr: &Projection, c: f64) -> Vec3 {
    let d = p - pr.point;
    if pr.dist > 1e-9 * c {
        d / pr.dist
    } else if d.dot(&pr.face_normal) < 0.0 {
        -pr.face_normal
    } else {
        pr.face_normal
    }
}

/// Penalty stiffness of a hit. Soft: s m* / dt_ref^2; element: s E' A / L.
pub fn stiffness(cfg: &ContactConfig, surf: &Surface, m_star: f64, seg: u32, dt_ref: f64) -> f64 {
    match cfg.penalty {
        PenaltyKind::Soft => cfg.penalty_scale * m_star / (dt_ref * dt_ref),
        PenaltyKind::Element => cfg.penalty_scale * surf.k_unit[seg as usize],
    }
}

/// Forces of the hits, f = (k depth - c_d v_n)+ n, in hit order. The depth is the exact
/// closest-point one; n and the point of the reaction come from the projection along the
/// smoothed normal (`smooth::along_normal`, `normals.segment` the nodal normals of `sb`,
/// or the closest point where that fails), averaged with the node's own normal
/// (`smooth::common_normal`, `normals.node` those of `nb`).
pub fn forces(
    hits: &[Hit],
    nb: &Body,
    sb: &Body,
    surf: &Surface,
    cfg: &ContactConfig,
    dt_ref: f64,
    normals: Normals<'_>,
) -> Vec<Push> {
    let c = 0.5 * (nb.def.section.thickness + sb.def.section.thickness);
    hits.iter()
        .filter_map(|h| {
            let i = h.node as usize;
            let p = nb.state.x[i];
            let seg = &surf.segments[h.segment as usize];
            // along the smoothed normal and the common normal, or the closest point
            let n_cp = normal(&p, &h.proj, c);
            let (n, weights) = match smoothed(
                &p,
                seg,
                &h.proj,
                &sb.state.x,
                normals.segment,
                &normals.node[i],
                &n_cp,
                c,
            ) {
                Some(s) => (s.direction, s.weights),
                None => (n_cp, h.proj.weights),
            };
            let m_star = nb.def.mass[i].min(surf.seg_mass[h.segment as usize]);
            let k = stiffness(cfg, surf, m_star, h.segment, dt_ref);
            let mut fn_ = k * h.depth;
            if cfg.damping_ratio > 0.0 {
                let mut vs = Vec3::zeros();
                for (q, &nd) in seg.nodes().iter().enumerate() {
                    vs += sb.state.v[nd as usize] * weights[q];
                }
                let vn = (nb.state.v[i] - vs).dot(&n);
                fn_ -= 2.0 * cfg.damping_ratio * (k * m_star).sqrt() * vn;
            }
            // a penalty pushes, never pulls
            (fn_ > 0.0 && fn_.is_finite()).then(|| Push {
                hit: *h,
                force: n * fn_,
                normal_force: fn_,
                weights,
            })
        })
        .collect()
}
