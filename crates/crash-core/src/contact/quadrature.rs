//! The segment pass (`ContactPass::Segments`): contact points that are not nodes.
//! Quadrature points on one body's (slave's) curved segments press on the other's
//! (master's) curved segments with the penalty potential (1/2) k_a g_a^2 per point;
//! each body is slave once with half the weight. docs/theory-contact.md, "Segment pass".
//!
//! Per point: x_a = sum N_k x_k + h_s n_sub (the slave's curved surface, `curved.rs`),
//! P the closest point of the master's flat segments (closest, ties: lowest index),
//! d = |x_a - P|, g = d - s h_m - c (h_m the master's bulge at P, s = +-1 the side of
//! x_a), force f = k_a (-g) grad g, grad g = (x_a - P)/d - s grad h_m. The force and its
//! reaction act on one line (through x_a along f): on the slave's nodes with the weights
//! of the point where that line meets the slave's (sub-)triangle, on the master's with
//! those where it meets the master's, so momentum and angular momentum hold exactly and
//! rigid motions see the exact gradient of the potential.

use super::config::ContactConfig;
use super::curved::{
    body_bulge_bound, bulge, bulge_pullback, coefficients, corner_a_weights, corner_normals,
    sub_triangle,
};
use super::narrow::TIE;
use super::segment::{project, Projection, Segment};
use super::smooth::nodal_normals;
use super::stage::PairStats;
use super::surface::Surface;
use crate::body::Body;
use crate::Vec3;
use rayon::prelude::*;
use std::mem::take;

/// Target spacing of the quadrature points as a fraction of the contact distance c:
/// each (sub-)triangle edge is split into ceil(L / (SPACING c)) parts.
pub const SPACING: f64 = 0.5;
/// Most parts per (sub-)triangle edge (bounds the cost on coarse meshes).
pub const MAX_PARTS: usize = 24;
/// Master points are looked for at least this far beyond the flat contact distance, as
/// a share of c, and farther where the meshes' bulge bounds are larger (coarse curved
/// meshes: a level-1 sphere of R 30 mm bulges 1.6 mm off its facets, 1.3 c).
pub const BULGE_REACH: f64 = 0.25;
/// Slave segments per task.
const SEG_CHUNK: usize = 256;

/// One active quadrature point.
#[derive(Debug, Clone)]
pub struct PointPush {
    pub slave_seg: u32,
    pub master_seg: u32,
    /// Forces on the slave's and the master's nodes [N] (they sum to zero; a node may
    /// appear more than once).
    pub slave_f: Vec<(u32, Vec3)>,
    pub master_f: Vec<(u32, Vec3)>,
    /// Resultant force on the slave [N].
    pub force: Vec3,
    pub normal_force: f64,
    pub depth: f64,
}

/// Points of one (sub-)triangle split into n x n: barycentric (u, v) of the small
/// triangles' centroids; each carries 1/n^2 of the area.
fn points(n: usize) -> impl Iterator<Item = (f64, f64)> {
    let nf = n as f64;
    (0..n).flat_map(move |i| {
        (0..n - i).flat_map(move |j| {
            let up = Some(((i as f64 + 1.0 / 3.0) / nf, (j as f64 + 1.0 / 3.0) / nf));
            let down =
                (i + j + 1 < n).then(|| ((i as f64 + 2.0 / 3.0) / nf, (j as f64 + 2.0 / 3.0) / nf));
            up.into_iter().chain(down)
        })
    })
}

fn seg_box(seg: &Segment, x: &[Vec3]) -> (Vec3, Vec3) {
    let mut lo = x[seg.nodes[0] as usize];
    let mut hi = lo;
    for &n in &seg.nodes()[1..] {
        lo = lo.inf(&x[n as usize]);
        hi = hi.sup(&x[n as usize]);
    }
    (lo, hi)
}

fn box_gap(a: &(Vec3, Vec3), b: &(Vec3, Vec3)) -> f64 {
    let d = (b.0 - a.1).sup(&Vec3::zeros()) + (a.0 - b.1).sup(&Vec3::zeros());
    d.norm()
}

/// The master data of one candidate segment: its index, node box and bulge coefficients.
struct Master {
    j: u32,
    bx: (Vec3, Vec3),
    b: [[f64; 4]; 4],
    normals: [Vec3; 4],
    nodal: [bool; 4],
}

/// All active points of slave body `sb` against master body `mb`. `kappa`: penalty
/// stiffness per unit area of this direction (weight included); `xi`: damping ratio;
/// `mu`: areal mass for the damping.
#[allow(clippy::too_many_arguments)]
pub fn point_pushes(
    sb: &Body,
    ssurf: &Surface,
    mb: &Body,
    msurf: &Surface,
    normals: (&[Vec3], &[Vec3]),
    bulges: (f64, f64),
    cfg: &ContactConfig,
    kappa: f64,
    mu: f64,
) -> Vec<PointPush> {
    let (snorm, mnorm) = normals;
    let (hs_max, hm_max) = bulges;
    let c = 0.5 * (sb.def.section.thickness + mb.def.section.thickness);
    // a point is in contact only within c plus the master's bulge of its flat segments;
    // the slave's own points stand off its flat boxes by up to its bulge
    let reach = c + (BULGE_REACH * c).max(hm_max);
    let box_reach = reach + hs_max;
    let (mlo, mhi) = msurf.bounds();
    let mbox = (mlo.add_scalar(-box_reach), mhi.add_scalar(box_reach));
    let xs_ = &sb.state.x;
    let xm = &mb.state.x;
    let chunks: Vec<Vec<PointPush>> = ssurf
        .segments
        .par_chunks(SEG_CHUNK)
        .enumerate()
        .map(|(ci, segs)| {
            let mut out = Vec::new();
            let mut cand = Vec::new();
            let mut masters: Vec<Master> = Vec::new();
            for (k, seg) in segs.iter().enumerate() {
                let js = (ci * SEG_CHUNK + k) as u32;
                let sbx = seg_box(seg, xs_);
                if box_gap(&sbx, &mbox) > 0.0 {
                    continue;
                }
                // master segments whose stored box meets the slave's box grown by the
                // slave's half-thickness and the bulge reach
                let g = 0.5 * sb.def.section.thickness + (BULGE_REACH * c).max(hm_max + hs_max);
                let lo = sbx.0.add_scalar(-g);
                let hi = sbx.1.add_scalar(g);
                msurf.query([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z], &mut cand);
                cand.sort_unstable();
                masters.clear();
                for &j in &cand {
                    let ms = &msurf.segments[j as usize];
                    let bx = seg_box(ms, xm);
                    if box_gap(&sbx, &bx) >= box_reach {
                        continue;
                    }
                    let (normals, nodal) = corner_normals(ms, mnorm, xm);
                    masters.push(Master {
                        j,
                        bx,
                        b: coefficients(ms, xm, &normals),
                        normals,
                        nodal,
                    });
                }
                if masters.is_empty() {
                    continue;
                }
                slave_segment(
                    sb, ssurf, snorm, js, seg, mb, msurf, &masters, c, reach, kappa, mu, cfg,
                    &mut out,
                );
            }
            out
        })
        .collect();
    chunks.into_iter().flatten().collect()
}

#[allow(clippy::too_many_arguments)]
fn slave_segment(
    sb: &Body,
    ssurf: &Surface,
    snorm: &[Vec3],
    js: u32,
    seg: &Segment,
    mb: &Body,
    msurf: &Surface,
    masters: &[Master],
    c: f64,
    reach: f64,
    kappa: f64,
    mu: f64,
    cfg: &ContactConfig,
    out: &mut Vec<PointPush>,
) {
    let xs_ = &sb.state.x;
    let xm = &mb.state.x;
    let (sn, s_nodal) = corner_normals(seg, snorm, xs_);
    let sb_coef = coefficients(seg, xs_, &sn);
    let subs = if seg.count == 3 { 1 } else { 4 };
    for sub in 0..subs {
        let st = sub_triangle(seg, xs_, sub);
        let st0 = sub_triangle(seg, &sb.def.x0, sub);
        let area0 = 0.5 * (st0.b - st0.a).cross(&(st0.c - st0.a)).norm();
        let longest = [
            (st.b - st.a).norm(),
            (st.c - st.b).norm(),
            (st.a - st.c).norm(),
        ]
        .into_iter()
        .fold(0.0, f64::max);
        let n = ((longest / (SPACING * c)).ceil() as usize).clamp(1, MAX_PARTS);
        let wa = (kappa * area0) / (n * n) as f64;
        let nsub = st.unit_normal();
        let base = corner_a_weights(seg);
        for (u, v) in points(n) {
            let mut w = base;
            for q in 0..4 {
                w[q] += u * st.dw_du[q] + v * st.dw_dv[q];
            }
            let flat = st.a + (st.b - st.a) * u + (st.c - st.a) * v;
            let (hs, _) = bulge(&sb_coef, &w);
            let xa = flat + nsub * hs;
            // closest master segment (ties within TIE c: lowest index; `masters` sorted)
            let mut best: Option<(Projection, usize)> = None;
            let mut dmin = f64::INFINITY;
            for (mi, m) in masters.iter().enumerate() {
                let lb = box_gap(&(xa, xa), &m.bx);
                if lb >= reach || lb > dmin + TIE * c {
                    continue;
                }
                let pr = project(&xa, &msurf.segments[m.j as usize], xm);
                if pr.dist.is_nan() {
                    continue;
                }
                let better = match &best {
                    None => true,
                    Some((b, _)) => pr.dist < b.dist - TIE * c,
                };
                dmin = dmin.min(pr.dist);
                if better {
                    best = Some((pr, mi));
                }
            }
            let Some((pr, mi)) = best else { continue };
            if pr.dist >= reach || pr.dist <= 1e-9 * c {
                continue;
            }
            let m = &masters[mi];
            let ms = &msurf.segments[m.j as usize];
            let mt = sub_triangle(ms, xm, pr.sub as usize);
            let dir = (xa - pr.point) / pr.dist;
            let side = if dir.dot(&mt.unit_normal()) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            let (hm, dhm) = bulge(&m.b, &pr.weights);
            let gap = pr.dist - side * hm - c;
            if gap >= 0.0 {
                continue;
            }
            // exact gradient of g: by the slave point, by the master's nodes (the
            // closest point's distance; the bulge through the projection's weights, the
            // edges and the corner normals)
            let rho = xa - pr.point;
            let (gw, cg) = mt.corner_gradients(&dhm, &pr.bary, &rho);
            let grad = dir - gw * side;
            let mut gm: Vec<(u32, Vec3)> = Vec::with_capacity(32);
            for q in 0..ms.count as usize {
                gm.push((ms.nodes[q], -dir * pr.weights[q]));
            }
            let mut spread = [Vec3::zeros(); 4];
            mt.spread(ms, pr.sub as usize, &cg.map(|g| -g * side), &mut spread);
            for q in 0..ms.count as usize {
                gm.push((ms.nodes[q], spread[q]));
            }
            bulge_pullback(
                ms,
                m.j,
                msurf,
                xm,
                &m.normals,
                &m.nodal,
                &pr.weights,
                -side,
                &mut gm,
            );
            // the slave point moves with the facet, along its normal by hs, and with hs
            let mut spread = [Vec3::zeros(); 4];
            for q in 0..seg.count as usize {
                spread[q] = grad * w[q];
            }
            let pb = st.normal_pullback(&grad);
            st.spread(seg, sub, &pb.map(|g| g * hs), &mut spread);
            let mut gs: Vec<(u32, Vec3)> = Vec::with_capacity(32);
            for q in 0..seg.count as usize {
                gs.push((seg.nodes[q], spread[q]));
            }
            bulge_pullback(
                seg,
                js,
                ssurf,
                xs_,
                &sn,
                &s_nodal,
                &w,
                grad.dot(&nsub),
                &mut gs,
            );
            let k = wa;
            let mut phi = k * (-gap);
            if cfg.damping_ratio > 0.0 {
                let mut gdot = 0.0;
                for (nd, g) in &gs {
                    gdot += g.dot(&sb.state.v[*nd as usize]);
                }
                for (nd, g) in &gm {
                    gdot += g.dot(&mb.state.v[*nd as usize]);
                }
                let ma = mu * area0 / (n * n) as f64;
                phi -= 2.0 * cfg.damping_ratio * (k * ma).sqrt() * gdot;
            }
            if !(phi > 0.0 && phi.is_finite()) {
                continue;
            }
            let fnorm = phi * grad.norm();
            out.push(PointPush {
                slave_seg: js,
                master_seg: m.j,
                slave_f: gs.into_iter().map(|(nd, g)| (nd, g * phi)).collect(),
                master_f: gm.into_iter().map(|(nd, g)| (nd, g * phi)).collect(),
                force: grad * phi,
                normal_force: fnorm,
                depth: -gap,
            });
        }
    }
}

/// The segment pass of a pair of different bodies (indices `ia`, `ib`, surfaces `sa`,
/// `sb`): each body slave once with half the weight; stiffness per unit area
/// kappa = s mu / dt_ref^2 (the soft rule per area, mu the lighter areal mass).
pub(crate) fn segment_pair(
    bodies: &mut [Body],
    ia: usize,
    ib: usize,
    sa: &Surface,
    sb: &Surface,
    cfg: &ContactConfig,
    dt_ref: f64,
) -> PairStats {
    let (a, b) = (&bodies[ia], &bodies[ib]);
    let mu = sa.areal_mass.min(sb.areal_mass);
    let kappa = 0.5 * cfg.penalty_scale * mu / (dt_ref * dt_ref);
    // nodal normals once per pass (the same bits as `Surface::nodal_normal`) and how far
    // each body's curved surface can stand off its facets
    let (na, nb) = (nodal_normals(a), nodal_normals(b));
    let ha = body_bulge_bound(sa, &na, &a.state.x);
    let hb = body_bulge_bound(sb, &nb, &b.state.x);
    let first = point_pushes(a, sa, b, sb, (&na, &nb), (ha, hb), cfg, kappa, mu);
    let second = point_pushes(b, sb, a, sa, (&nb, &na), (hb, ha), cfg, kappa, mu);
    let mut st = PairStats::empty(a.def.id, b.def.id, first.len() + second.len());
    let thin = a.def.section.thickness.min(b.def.section.thickness);
    apply_points(bodies, ia, ib, &first, &mut st, true);
    apply_points(bodies, ib, ia, &second, &mut st, false);
    st.kin_a.settle_nodes();
    st.kin_b.settle_nodes();
    st.max_penetration_ratio = st.max_penetration / thin;
    st
}

/// Add the points of one direction of the segment pass: their node forces on the
/// slave's nodes (body `islave`) and the master's, sequentially in point order; what lands on
/// a kinematic body goes into the pair's `KinLoad` too.
fn apply_points(
    bodies: &mut [Body],
    islave: usize,
    imaster: usize,
    pushes: &[PointPush],
    st: &mut PairStats,
    slave_is_a: bool,
) {
    let (kin_s, kin_m) = (bodies[islave].def.kinematic, bodies[imaster].def.kinematic);
    let (mut l_s, mut l_m) = if slave_is_a {
        (take(&mut st.kin_a), take(&mut st.kin_b))
    } else {
        (take(&mut st.kin_b), take(&mut st.kin_a))
    };
    for p in pushes {
        for (body, fs, kin, l) in [
            (islave, &p.slave_f, kin_s, &mut l_s),
            (imaster, &p.master_f, kin_m, &mut l_m),
        ] {
            let b = &mut bodies[body];
            for &(n, f) in fs {
                b.state.f_contact[n as usize] += f;
                if kin {
                    l.push(n, f, b.state.v[n as usize], b.def.program[n as usize]);
                }
            }
        }
        st.max_penetration = st.max_penetration.max(p.depth);
        st.normal_force += p.normal_force;
        st.force_on_a += if slave_is_a { p.force } else { -p.force };
    }
    if slave_is_a {
        (st.kin_a, st.kin_b) = (l_s, l_m);
    } else {
        (st.kin_b, st.kin_a) = (l_s, l_m);
    }
}
