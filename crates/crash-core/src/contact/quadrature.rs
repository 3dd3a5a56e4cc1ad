//! The segment pass (`ContactPass::Segments`): contact points that are not nodes.
//! Quadrature points on one body's (slave's) curved segments press on the other's
//! (master's) curved segments with the penalty potential k_a c^2 psi(-g_a / c) per
//! point (`stiffening.rs`: (1/2) k_a g_a^2 when shallow, stiffer with depth); the finer
//! body is the slave (`segpair::slave_is_a`). docs/theory-contact.md, "Segment pass".
//!
//! Per point: x_a = sum N_k x_k + h_s n_sub (the slave's curved surface, `curved.rs`),
//! P the closest point of the master's flat segments (closest, ties: lowest index),
//! d = |x_a - P|, g = d - s h_m - c (h_m the master's bulge at P, s = +-1 the side of
//! x_a), force f = k_a c phi(-g / c) grad g, grad g = (x_a - P)/d - s grad h_m. The force and its
//! reaction act on one line (through x_a along f): on the slave's nodes with the weights
//! of the point where that line meets the slave's (sub-)triangle, on the master's with
//! those where it meets the master's, so momentum and angular momentum hold exactly and
//! rigid motions see the exact gradient of the potential.

use super::config::ContactConfig;
use super::curved::{
    bulge, bulge_bound, bulge_parts, corner_a_weights, node_box, normal_rate, sub_triangle,
    sub_triangle_at, Curved, NearCurved, NormalOf,
};
use super::narrow::TIE;
use super::reach::{
    box_gap, box_gap2, gap_at_least, nearest, rule_again, CurvedAt, Master, MasterCurved, Pick,
    Reach, Slab, Wide,
};
use super::segment::{Corners, Segment};
use super::stiffening;
use super::surface::Surface;
use super::verlet::{box_list, NodeList, SegmentLists};
use crate::body::Body;
use crate::Vec3;
use rayon::prelude::*;

/// Target spacing of the quadrature points as a fraction of the contact distance c:
/// each (sub-)triangle edge is split into ceil(L / (SPACING c)) parts. At c a point
/// costs a quarter of c/2's and the oblique impacts stay within issue 12's bounds
/// (docs/theory-contact.md, spacing table).
pub const SPACING: f64 = 1.0;
/// Most parts per (sub-)triangle edge (bounds the cost on coarse meshes).
pub const MAX_PARTS: usize = 24;
/// Master points are looked for at least this far beyond the flat contact distance, as
/// a share of c, and farther where the meshes' bulge bounds are larger (coarse curved
/// meshes: a level-1 sphere of R 30 mm bulges 1.6 mm off its facets, 1.3 c).
pub const BULGE_REACH: f64 = 0.25;
/// Most slave segments per task.
const SEG_CHUNK: usize = 256;
/// Tasks per thread of the pool the slave segments are cut into (fewer, larger ones
/// when there are few segments: at least one query group each).
const TASKS_PER_THREAD: usize = 4;
/// Columns of a strip (two points each) whose points search one list of masters.
const BLOCK: usize = 4;
/// Fewest slave segments per task (a task's size is a multiple of it).
const TASK_GRAIN: usize = 8;

/// One active quadrature point: its forces on the corner nodes of its two segments. The
/// bulge terms through the corner normals are not here: they go to `NormalLoad`s,
/// summed per normal and pulled back once per pass.
#[derive(Debug, Clone)]
pub struct PointPush {
    pub slave_seg: u32,
    pub master_seg: u32,
    /// Forces on the slave's and the master's corner nodes [N] (the first `*_count`).
    pub slave_f: [(u32, Vec3); 4],
    pub slave_count: u8,
    pub master_f: [(u32, Vec3); 4],
    pub master_count: u8,
    /// Resultant force on the slave [N].
    pub force: Vec3,
    pub normal_force: f64,
    pub depth: f64,
}

/// A load on one unit normal of a body (the derivative of the potential by that normal,
/// at one point) [N]: `curved::normal_pullback` turns it into node forces.
#[derive(Debug, Clone, Copy)]
pub struct NormalLoad {
    pub of: NormalOf,
    pub tau: Vec3,
}

/// The points of one direction of the pass, and the loads they put on the slave's and
/// the master's normals, all in point order.
#[derive(Debug, Default)]
pub struct Points {
    pub pushes: Vec<PointPush>,
    pub slave_loads: Vec<NormalLoad>,
    pub master_loads: Vec<NormalLoad>,
}

/// Points of one (sub-)triangle split into n x n, strip i of n (u between i/n and
/// (i+1)/n): barycentric (u, v) of the small triangles' centroids; each carries 1/n^2 of
/// the area. Strips 0..n in turn give every point once.
fn strip_points(n: usize, i: usize) -> impl Iterator<Item = (f64, f64)> {
    let nf = n as f64;
    (0..n - i).flat_map(move |j| {
        let up = Some(((i as f64 + 1.0 / 3.0) / nf, (j as f64 + 1.0 / 3.0) / nf));
        let down =
            (i + j + 1 < n).then(|| ((i as f64 + 2.0 / 3.0) / nf, (j as f64 + 2.0 / 3.0) / nf));
        up.into_iter().chain(down)
    })
}

/// All active points of slave body `sb` against master body `mb`. `master_near`: the
/// box of the master's segments that can touch the slave (every master a point can
/// touch lies in it); `curved`: both bodies' segments that can touch the other
/// (`reach::near_sets`; slave's, master's): the slave's are the segments searched;
/// `kappa`: penalty stiffness per unit area of this direction (weight included); `mu`:
/// areal mass for the damping; `slaves`: the slave segments whose points are wanted
/// (None: all; a split group's view wants those that can push its owned nodes, and
/// each point's result does not depend on which others are searched); `lists`: each
/// slave segment's list of master candidates, kept from pass to pass (`verlet::box_list`:
/// the same candidates as a tree query, the same bits).
#[allow(clippy::too_many_arguments)]
pub fn point_pushes(
    sb: &Body,
    ssurf: &Surface,
    mb: &Body,
    msurf: &Surface,
    master_near: (Vec3, Vec3),
    curved: (&NearCurved, &NearCurved),
    cfg: &ContactConfig,
    kappa: f64,
    mu: f64,
    slaves: Option<&[bool]>,
    lists: &mut SegmentLists,
) -> Vec<Points> {
    let (scurv, mcurv) = curved;
    let (hs_max, hm_max) = (scurv.bound, mcurv.bound);
    let c = 0.5 * (sb.def.section.thickness + mb.def.section.thickness);
    // a point is in contact only within c plus the master's bulge of its flat segments;
    // the slave's own points stand off its flat boxes by up to its bulge
    let reach = c + (BULGE_REACH * c).max(hm_max);
    // no master presses on a point farther than c + its bulge bound (gap d - s h_m - c
    // >= 0; the margin covers the bulge's round-off): `reach::nearest` projects only the
    // masters within that and gives the rule's answer wherever the gap is negative
    let touch = ((c + hm_max) * (1.0 + 1e-9)).min(reach);
    let box_reach = reach + hs_max;
    // a master can press on a point of a slave segment only if their node boxes lie
    // within touch plus the slave's bulge bound
    let press = touch + hs_max;
    let press2 = press * press;
    let (mlo, mhi) = master_near;
    let mbox = (mlo.add_scalar(-press), mhi.add_scalar(press));
    let xm = &mb.state.x;
    // the slave segments searched: those wanted whose node box meets the master's near
    // box grown by `press` (the rest hold no point that can touch), in index order
    let wanted = |j: &u32| slaves.is_none_or(|w| w.get(*j as usize).copied().unwrap_or(false));
    let (ids, boxes): (Vec<u32>, Vec<(Vec3, Vec3)>) = scurv
        .segs()
        .iter()
        .zip(scurv.boxes())
        .filter(|(j, sbx)| {
            let gap = box_gap(sbx, &mbox);
            wanted(j) && (gap.is_nan() || gap <= 0.0)
        })
        .map(|(&js, &sbx)| (js, sbx))
        .unzip();
    // with each its kept list of master candidates
    let mut passing: Vec<(u32, (Vec3, Vec3), &mut NodeList)> = ids
        .iter()
        .zip(boxes)
        .zip(lists.for_segments(&ids))
        .map(|((&js, sbx), list)| (js, sbx, list))
        .collect();
    // tasks of a few grains each, a few tasks per thread: the points cluster
    // where the bodies touch, so tasks much larger than that leave a thread idle
    let per_task = passing
        .len()
        .div_ceil(TASKS_PER_THREAD * rayon::current_num_threads());
    let chunk = per_task
        .next_multiple_of(TASK_GRAIN)
        .clamp(TASK_GRAIN, SEG_CHUNK);
    passing
        .par_chunks_mut(chunk)
        .map(|passing| {
            let mut out = Points::default();
            let mut cand = Vec::new();
            let mut masters: Vec<Master> = Vec::new();
            let mut extra: Vec<Curved> = Vec::new();
            let mut culled = (Vec::new(), Vec::new());
            // the rule's candidates: master segments whose stored box meets the slave's
            // box grown by the slave's half-thickness and the bulge reach (`g`); of
            // those, the ones that can press: within `press` (their stored box holds their
            // node box grown by the master's half-thickness, so the query grown by `gp`
            // finds them; never more than `g` finds)
            let g = 0.5 * sb.def.section.thickness + (BULGE_REACH * c).max(hm_max + hs_max);
            let gp = g.min(0.5 * sb.def.section.thickness + (touch - c) + hs_max + 1e-6 * c);
            let query_box = |sbx: &(Vec3, Vec3)| {
                let (lo, hi) = (sbx.0.add_scalar(-gp), sbx.1.add_scalar(gp));
                ([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z])
            };
            for (js, sbx, list) in passing.iter_mut() {
                let (js, sbx) = (*js, *sbx);
                let seg = &ssurf.segments[js as usize];
                let (lo, hi) = query_box(&sbx);
                // the segments whose stored box meets the query box, ascending
                box_list(list, msurf, (&lo, &hi), &mut cand);
                masters.clear();
                extra.clear();
                // coordinates' size, for the slabs' round-off margin
                let scale = sbx.0.abs().max().max(sbx.1.abs().max()) + box_reach;
                for &j in &cand {
                    let ms = &msurf.segments[j as usize];
                    let bx = node_box(ms, xm);
                    if gap_at_least(box_gap2(&sbx, &bx), press, press2) {
                        continue;
                    }
                    let at = Corners::of(ms, xm);
                    let cv = match mcurv.index(j) {
                        Some(k) => CurvedAt::Near(k),
                        None => {
                            extra.push(Curved::of(ms, msurf, xm));
                            CurvedAt::Extra(extra.len() - 1)
                        }
                    };
                    masters.push(Master {
                        j,
                        bx,
                        at,
                        cv,
                        slab: Slab::of(&at, scale, c),
                    });
                }
                if masters.is_empty() {
                    continue;
                }
                let scv = scurv.get(js, ssurf, &sb.state.x);
                let mc = MasterCurved {
                    near: mcurv,
                    extra: &extra,
                };
                let wide = Wide {
                    msurf,
                    xm,
                    mcurv,
                    sbx,
                    grow: g,
                    box_reach,
                    scale,
                    c,
                };
                slave_segment(
                    sb,
                    ssurf,
                    js,
                    seg,
                    &scv,
                    mb,
                    msurf,
                    (&masters, &mc, &wide),
                    c,
                    Reach {
                        reach,
                        touch,
                        tie: TIE * c,
                    },
                    kappa,
                    mu,
                    cfg,
                    &mut culled,
                    &mut out,
                );
            }
            out
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn slave_segment(
    sb: &Body,
    ssurf: &Surface,
    js: u32,
    seg: &Segment,
    scv: &Curved,
    mb: &Body,
    msurf: &Surface,
    masters: (&[Master], &MasterCurved, &Wide),
    c: f64,
    r: Reach,
    kappa: f64,
    mu: f64,
    cfg: &ContactConfig,
    (keep, block): &mut (Vec<usize>, Vec<usize>),
    out: &mut Points,
) {
    let xs_ = &sb.state.x;
    let xm = &mb.state.x;
    let (masters, mcurv, wide) = masters;
    let (sn, s_nodal, sb_coef) = (scv.normals, scv.nodal, scv.b);
    let hs_bound = bulge_bound(&sb_coef);
    let (reach, touch) = (r.reach, r.touch);
    let near = Near {
        masters,
        touch,
        hs_bound,
    };
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
        let flat_at = |u: f64, v: f64| st.a + (st.b - st.a) * u + (st.c - st.a) * v;
        for i in 0..n {
            // the masters that can press on some point of this strip: the strip's
            // corners' box grown by the slave's bulge bound holds its points, and their
            // hull within the bulge bound too; a master whose box or slab lies at `touch`
            // or beyond from them would be skipped at every point (if none is left, the
            // strip's points are dropped either way: `reach::nearest`)
            let (u0, u1) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
            let corners = [
                flat_at(u0, 0.0),
                flat_at(u1, 0.0),
                flat_at(u0, 1.0 - u0),
                flat_at(u1, 1.0 - u1),
            ];
            let strip = near.cull(&corners, 0..masters.len(), keep);
            if keep.is_empty() {
                continue;
            }
            // a long strip in blocks of BLOCK columns (two points each), each point
            // searching the strip's masters that come within touch of its block: on a
            // coarse mesh most of a long strip lies away from the contact
            let mut at_block = usize::MAX;
            for (k, (u, v)) in strip_points(n, i).enumerate() {
                if k / (2 * BLOCK) != at_block {
                    at_block = k / (2 * BLOCK);
                    if n - i <= BLOCK {
                        // a short strip is its one block
                        block.clone_from(keep);
                    } else {
                        let (j0, j1) = (at_block * BLOCK, ((at_block + 1) * BLOCK).min(n - i));
                        let (v0, v1) = (j0 as f64 / n as f64, j1 as f64 / n as f64);
                        let bc = [
                            flat_at(u0, v0),
                            flat_at(u1, v0),
                            flat_at(u0, v1),
                            flat_at(u1, v1),
                        ];
                        near.cull(&bc, keep.iter().copied(), block);
                    }
                }
                if block.is_empty() {
                    continue;
                }
                let mut w = base;
                for q in 0..4 {
                    w[q] += u * st.dw_du[q] + v * st.dw_dv[q];
                }
                let flat = st.a + (st.b - st.a) * u + (st.c - st.a) * v;
                let (hs, _) = bulge(&sb_coef, &w);
                let xa = flat + nsub * hs;
                // closest master segment (ties within TIE c: lowest index; `masters` sorted)
                let again;
                let (pr, m, mcv) = match nearest(&xa, masters, block, r) {
                    Pick::Found(pr, mi) => (pr, &masters[mi], mcurv.of(&masters[mi])),
                    Pick::Drop => continue,
                    Pick::Rerun => {
                        let Some(found) = rule_again(&xa, &strip, wide, r) else {
                            continue;
                        };
                        again = found;
                        (again.0, &again.1, &again.2)
                    }
                };
                if pr.dist >= reach || pr.dist <= 1e-9 * c {
                    continue;
                }
                let ms = &msurf.segments[m.j as usize];
                let mt = sub_triangle_at(&m.at, pr.sub as usize);
                let dir = (xa - pr.point) / pr.dist;
                let side = if dir.dot(&mt.unit_normal()) >= 0.0 {
                    1.0
                } else {
                    -1.0
                };
                let (hm, dhm) = bulge(&mcv.b, &pr.weights);
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
                // g by the master's corner nodes: the closest point's distance, the bulge
                // through the projection's weights and through the edges; the part through
                // the corner normals as loads on those normals
                let mut gm = [Vec3::zeros(); 4];
                for q in 0..ms.count as usize {
                    gm[q] = -dir * pr.weights[q];
                }
                mt.spread(ms, pr.sub as usize, &cg.map(|g| -g * side), &mut gm);
                let (direct, m_tau) = bulge_parts(ms, xm, &mcv.normals, &pr.weights, -side);
                for q in 0..4 {
                    gm[q] += direct[q];
                }
                // the slave point moves with the facet, along its normal by hs, and with hs
                let mut gs = [Vec3::zeros(); 4];
                for q in 0..seg.count as usize {
                    gs[q] = grad * w[q];
                }
                let pb = st.normal_pullback(&grad);
                st.spread(seg, sub, &pb.map(|g| g * hs), &mut gs);
                let (direct, s_tau) = bulge_parts(seg, xs_, &sn, &w, grad.dot(&nsub));
                for q in 0..4 {
                    gs[q] += direct[q];
                }
                // the stiffening law (`stiffening.rs`): k c phi(-g / c), = k (-g) when shallow
                let k = wa;
                let mut phi = k * c * stiffening::force(-gap / c);
                if cfg.damping_ratio > 0.0 {
                    let mut gdot = 0.0;
                    for q in 0..seg.count as usize {
                        gdot += gs[q].dot(&sb.state.v[seg.nodes[q] as usize]);
                        let of = NormalOf::of_corner(seg, js, &s_nodal, q);
                        gdot += s_tau[q].dot(&normal_rate(of, ssurf, xs_, &sb.state.v));
                    }
                    for q in 0..ms.count as usize {
                        gdot += gm[q].dot(&mb.state.v[ms.nodes[q] as usize]);
                        let of = NormalOf::of_corner(ms, m.j, &mcv.nodal, q);
                        gdot += m_tau[q].dot(&normal_rate(of, msurf, xm, &mb.state.v));
                    }
                    let ma = mu * area0 / (n * n) as f64;
                    phi -= 2.0 * cfg.damping_ratio * (k * ma).sqrt() * gdot;
                }
                if !(phi > 0.0 && phi.is_finite()) {
                    continue;
                }
                for q in 0..seg.count as usize {
                    out.slave_loads.push(NormalLoad {
                        of: NormalOf::of_corner(seg, js, &s_nodal, q),
                        tau: s_tau[q] * phi,
                    });
                }
                for q in 0..ms.count as usize {
                    out.master_loads.push(NormalLoad {
                        of: NormalOf::of_corner(ms, m.j, &mcv.nodal, q),
                        tau: m_tau[q] * phi,
                    });
                }
                out.pushes.push(PointPush {
                    slave_seg: js,
                    master_seg: m.j,
                    slave_f: std::array::from_fn(|q| (seg.nodes[q], gs[q] * phi)),
                    slave_count: seg.count,
                    master_f: std::array::from_fn(|q| (ms.nodes[q], gm[q] * phi)),
                    master_count: ms.count,
                    force: grad * phi,
                    normal_force: phi * grad.norm(),
                    depth: -gap,
                });
            }
        }
    }
}

/// The masters a region of a slave segment's points can touch.
struct Near<'a> {
    masters: &'a [Master],
    touch: f64,
    hs_bound: f64,
}

impl Near<'_> {
    /// Of the masters `from` (positions in `masters`, in order), into `out`, those whose
    /// box and slab come within touch of the region: the hull of its flat `corners`
    /// grown by the slave's bulge bound holds its points. A master left out lies at
    /// touch or beyond from every point of the region, which `reach::nearest` skips
    /// either way (no bits depend on the region's size). Returns the region's box.
    fn cull(
        &self,
        corners: &[Vec3; 4],
        from: impl Iterator<Item = usize>,
        out: &mut Vec<usize>,
    ) -> (Vec3, Vec3) {
        let (mut lo, mut hi) = (corners[0], corners[0]);
        for p in &corners[1..] {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let region = (lo.add_scalar(-self.hs_bound), hi.add_scalar(self.hs_bound));
        let touch2 = self.touch * self.touch;
        out.clear();
        out.extend(from.filter(|&mi| {
            let m = &self.masters[mi];
            !gap_at_least(box_gap2(&region, &m.bx), self.touch, touch2)
                && m.slab
                    .is_none_or(|sl| sl.gap_hull(corners, self.hs_bound) < self.touch)
        }));
        region
    }
}
