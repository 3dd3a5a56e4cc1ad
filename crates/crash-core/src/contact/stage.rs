//! The contact stage of a group's step: level i (candidate body pairs), level ii (per
//! pair, both passes), penalty forces into `Body::f_contact`, the contact stable step,
//! per-pair statistics, the tunnelling guard and the initial-penetration report.
//!
//! Determinism: pairs run in sorted (body id, body id) order, each pair's first pass
//! (nodes of the lower id against segments of the higher) before its second, hits in
//! node order; forces are added to nodes sequentially in exactly that order. Only pairs
//! with a contact add anything, so a body's forces depend only on the bodies it touches.

use super::broad::{candidate_pairs, BodyBox};
use super::config::{
    ContactConfig, ContactPass, PenaltyKind, SpeedRule, CLOSING_FRACTION, REFERENCE_SAFETY,
};
use super::figures::NodeFigures;
use super::narrow::{forces, Normals, Push};
use super::passes::{all_pair_passes, PairJob};
use super::segment::Segment;
use super::segpair::segment_pair;
use super::stats::PairStats;
use super::stiffening;
use super::surface::Surface;
use super::sweep::{closing_speed, BodySpeed};
use super::verlet::{NodeLists, PairLists};
use crate::body::Body;
use crate::error::Fault;
use crate::Vec3;
use std::collections::BTreeMap;
use std::mem::take;

/// Search caches of a group (R-trees, Verlet reference positions) and the last pass's
/// statistics. Not part of the physical state: rebuilt lazily after deserialization.
#[derive(Debug, Clone, Default)]
pub struct ContactState {
    surfaces: BTreeMap<u32, Surface>,
    /// Nodal normals per body, valid at the nodes the current pass reads.
    normals: BTreeMap<u32, Vec<Vec3>>,
    /// Node candidate lists per pass (node body, segment body).
    lists: BTreeMap<(u32, u32), NodeLists>,
    /// The segment pass's kept lists per pair (a, b): the slave segments' masters, a's
    /// against b and b's against a, and the near sets' queries.
    seg_lists: BTreeMap<(u32, u32), PairLists>,
    stats: Vec<PairStats>,
}

impl ContactState {
    /// Per-pair statistics of the last force pass, sorted by (a, b).
    pub fn stats(&self) -> &[PairStats] {
        &self.stats
    }

    /// Total number of tree builds so far (for benchmarks and diagnostics).
    pub fn tree_builds(&self) -> u64 {
        self.surfaces.values().map(|s| s.builds).sum()
    }
}

/// Candidate pairs among the contact bodies (indices into `bodies`), sorted by ids,
/// with self pairs for bodies that have self-contact on. Pairs of two kinematic bodies
/// are left out: contact cannot move either (and such a pair may meet in several
/// groups as read-only copies: it must not be counted twice).
pub(crate) fn pairs_of(
    bodies: &[Body],
    cfg: &ContactConfig,
    bounds: &[(Vec3, Vec3)],
) -> Vec<(usize, usize)> {
    let index: BTreeMap<u32, usize> = bodies
        .iter()
        .enumerate()
        .filter(|(_, b)| b.def.contact)
        .map(|(k, b)| (b.def.id, k))
        .collect();
    let boxes: Vec<BodyBox> = index
        .values()
        .map(|&k| BodyBox::with_bounds(&bodies[k], bounds[k]))
        .collect();
    let mut pairs: Vec<(u32, u32)> = candidate_pairs(&boxes, cfg.margin);
    pairs.extend(
        index
            .iter()
            .filter(|(_, &k)| bodies[k].def.self_contact)
            .map(|(&id, _)| (id, id)),
    );
    pairs.sort_unstable();
    pairs
        .into_iter()
        .filter_map(|(a, b)| Some((*index.get(&a)?, *index.get(&b)?)))
        .filter(|&(a, b)| !(bodies[a].def.kinematic && bodies[b].def.kinematic))
        .collect()
}

/// `body`'s surface, made if new and refreshed for this pass (`Surface::refresh_given`:
/// `given` and `step` let it use the integration's figures).
pub(crate) fn ensure_surface<'s>(
    surfaces: &'s mut BTreeMap<u32, Surface>,
    body: &Body,
    skin: f64,
    given: Option<&NodeFigures>,
    step: Option<u64>,
) -> &'s mut Surface {
    let s = surfaces
        .entry(body.def.id)
        .or_insert_with(|| Surface::new(body));
    if !s.fits(body) {
        *s = Surface::new(body);
    }
    s.refresh_given(body, skin, given, step);
    s
}

/// Nodes per task of the stage's whole-body passes (boxes, speeds).
pub(crate) const PAR_CHUNK: usize = 2048;

/// Box of every contact body's nodes (other bodies get an empty box).
pub fn body_bounds(bodies: &[Body]) -> Vec<(Vec3, Vec3)> {
    bodies
        .iter()
        .map(|b| {
            if b.def.contact {
                crate::mesh::bounds(&b.state.x)
            } else {
                (Vec3::zeros(), Vec3::zeros())
            }
        })
        .collect()
}

/// Element-form stable step of nodes of `nb` against segments of `surf`: a two-mass
/// spring k between m* and the segment gives omega^2 <= 2 k / m*, so dt = sqrt(2 m*/k).
pub(crate) fn element_form_dt(cfg: &ContactConfig, nb: &Surface, surf: &Surface) -> f64 {
    let s = cfg.penalty_scale;
    let m_over_k = (nb.min_mass * surf.inv_k).min(surf.mass_per_k) / s;
    (2.0 * m_over_k).sqrt()
}

/// Compute contact forces at the current positions into `f_contact` of every contact
/// body. `bounds[k]` is body k's node box at these positions (the integration has it).
/// `element_dt[k]` is body k's element critical step of this force pass (sets the
/// soft penalty's reference step: REFERENCE_SAFETY times the smaller of the pair's, and
/// of the pair's closing-speed step under `SpeedRule::LimitDt`). `h` is the step that
/// led to the current positions (0 at the start) and `step` its number: every node of a
/// candidate pair is first checked for a crossing within that step (a crossing is a
/// `Fault::PassThrough`). Returns the contact stable step per body (infinite where
/// contact sets no limit).
pub fn contact_forces(
    bodies: &mut [Body],
    cfg: &ContactConfig,
    state: &mut ContactState,
    element_dt: &[f64],
    bounds: &[(Vec3, Vec3)],
    h: f64,
    step: u64,
) -> Result<Vec<f64>, Fault> {
    let given = Given {
        closing: None,
        figures: &[],
        counted: &[],
        counted_segments: &[],
        slave_segments: &[],
    };
    contact_forces_given(bodies, cfg, state, element_dt, bounds, h, step, given)
}

/// What a caller of the stage already knows: the closing-speed steps of a split
/// group's pairs (`closing`: then they are not computed), and the figures the
/// integration took of each body's nodes in the step that led here (`figures`, by body
/// index; empty or None where it took none), and which nodes' pushes the statistics
/// book (`counted`, by body index then node; empty: every node): a split group's
/// views overlap, and each push is booked by the holder owning its slave node; under
/// the segment pass, by the holder counting the element of its point's slave segment
/// (`counted_segments`, by body index then segment; empty: every segment), and only
/// the slave segments `slave_segments` holds are searched (empty: all).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Given<'a> {
    pub closing: Option<&'a BTreeMap<(u32, u32), Option<f64>>>,
    pub figures: &'a [Option<NodeFigures>],
    pub counted: &'a [Vec<bool>],
    pub counted_segments: &'a [Vec<bool>],
    pub slave_segments: &'a [Vec<bool>],
}

/// The closing-speed step of a pair of different bodies (`SpeedRule::LimitDt`): a
/// fraction of the mean thickness over the pair's closing speed, None when they do not
/// close. `sa`, `sb`: the bodies' `BodySpeed`.
pub(crate) fn closing_dt(a: &Body, b: &Body, sa: &BodySpeed, sb: &BodySpeed) -> Option<f64> {
    let c = 0.5 * (a.def.section.thickness + b.def.section.thickness);
    closing_dt_of(c, closing_speed(a, b, sa, sb))
}

/// The penalty has a usable reference step `dt` for a pair: the soft penalty needs a
/// finite positive one (none: two kinematic bodies, which contact cannot move) and
/// skips the pair without it; the other penalties need none.
pub fn has_reference(penalty: PenaltyKind, dt: f64) -> bool {
    penalty != PenaltyKind::Soft || (dt.is_finite() && dt > 0.0)
}

/// The closing-speed step of a pair of mean thickness `c` closing at `v` (None: they do
/// not close).
pub fn closing_dt_of(c: f64, v: f64) -> Option<f64> {
    (v > 0.0).then(|| CLOSING_FRACTION * c / v)
}

/// `contact_forces`, with the closing-speed steps of the pairs (by body ids, None where
/// they do not close) given by `closing` instead of computed from `bodies`: a body split
/// into parts sees only a contact halo of the others, while the closing speed is a
/// figure of the whole bodies (`partition::contact`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn contact_forces_given(
    bodies: &mut [Body],
    cfg: &ContactConfig,
    state: &mut ContactState,
    element_dt: &[f64],
    bounds: &[(Vec3, Vec3)],
    h: f64,
    step: u64,
    given: Given<'_>,
) -> Result<Vec<f64>, Fault> {
    let closing = given.closing;
    let fig = |k: usize| given.figures.get(k).and_then(|f| f.as_ref());
    let mut dt = vec![f64::INFINITY; bodies.len()];
    state.stats.clear();
    for b in bodies.iter_mut() {
        if b.def.contact && cfg.enabled {
            // zeroed on the pool: a serial memset of a large body's forces was a tenth
            // of the showcase's contact stage at 2 threads
            use rayon::prelude::*;
            let f = &mut b.state.f_contact;
            f.resize(b.state.x.len(), Vec3::zeros());
            f.par_chunks_mut(PAR_CHUNK)
                .for_each(|c| c.fill(Vec3::zeros()));
        } else if !b.state.f_contact.is_empty() {
            b.state.f_contact.clear();
        }
    }
    if !cfg.enabled {
        return Ok(dt);
    }
    let pairs = pairs_of(bodies, cfg, bounds);
    // node lists only for this pass's pairs (a floor under many bodies would otherwise
    // keep a list per node for every body that ever came near it)
    let live: std::collections::BTreeSet<(u32, u32)> = pairs
        .iter()
        .flat_map(|&(a, b)| {
            let (a, b) = (bodies[a].def.id, bodies[b].def.id);
            [(a, b), (b, a)]
        })
        .collect();
    state.lists.retain(|k, _| live.contains(k));
    state.seg_lists.retain(|k, _| live.contains(k));
    // each body of a pair once per pass, however many pairs it is in (a floor under many
    // bodies): its surface, and its mean velocity when the closing speed is needed
    let mut in_pairs: Vec<usize> = pairs.iter().flat_map(|&(a, b)| [a, b]).collect();
    in_pairs.sort_unstable();
    in_pairs.dedup();
    // the speeds (momentum and velocity boxes, each on the pool) beside the surface
    // refreshes: both sides fill the threads
    let bodies_ = &*bodies;
    let surfaces = &mut state.surfaces;
    let ((), means) = rayon::join(
        || {
            for &k in &in_pairs {
                let skin = cfg.margin_for(&bodies_[k]);
                ensure_surface(surfaces, &bodies_[k], skin, fig(k), Some(step));
            }
        },
        || {
            let want = cfg.speed_rule == SpeedRule::LimitDt && closing.is_none();
            let speed = |&k: &usize| (k, BodySpeed::of_given(&bodies_[k], fig(k)));
            want.then(|| in_pairs.iter().map(speed).collect::<Vec<_>>())
        },
    );
    let mut speeds = vec![BodySpeed::default(); bodies.len()];
    for (k, u) in means.into_iter().flatten() {
        speeds[k] = u;
    }
    // every pair's limits and whether its search runs (serial: a few figures a pair),
    // then the passes of all pairs at once on the pool, then the rest pair by pair
    let mut plans = Vec::with_capacity(pairs.len());
    for &(ia, ib) in &pairs {
        let (a, b) = (&bodies[ia], &bodies[ib]);
        let (Some(sa), Some(sb)) = (state.surfaces.get(&a.def.id), state.surfaces.get(&b.def.id))
        else {
            continue;
        };
        // the pair's limits on both bodies' steps (booked once the crossing check passed)
        let mut limit = f64::INFINITY;
        if cfg.penalty == PenaltyKind::Element {
            limit = element_form_dt(cfg, sa, sb).min(element_form_dt(cfg, sb, sa));
        }
        let self_pair = ia == ib;
        let mut pair_dt = element_dt[ia].min(element_dt[ib]);
        let mut find = has_reference(cfg.penalty, pair_dt);
        if find && cfg.speed_rule == SpeedRule::LimitDt && !self_pair {
            // given (a split group's views): absent or None, the pair does not close
            let d = match closing {
                Some(m) => m.get(&(a.def.id, b.def.id)).copied().flatten(),
                None => closing_dt(a, b, &speeds[ia], &speeds[ib]),
            };
            if let Some(d) = d {
                limit = limit.min(d);
                pair_dt = pair_dt.min(d);
            }
        }
        let dt_ref = REFERENCE_SAFETY * pair_dt;
        find = find && has_reference(cfg.penalty, dt_ref);
        let segment_pass = cfg.pass == ContactPass::Segments && !self_pair;
        plans.push((
            limit,
            pair_dt,
            dt_ref,
            segment_pass,
            PairJob {
                ia,
                ib,
                // the crossing check of both passes first (a crossing is the fault), with
                // the search of both passes when the node passes follow
                find: find && !segment_pass,
            },
            find,
        ));
    }
    let jobs: Vec<PairJob> = plans.iter().map(|p| p.4).collect();
    let all_hits = all_pair_passes(bodies, &state.surfaces, &mut state.lists, &jobs, h, step)?;
    for ((limit, pair_dt, dt_ref, segment_pass, job, find), (hits_a, hits_b)) in
        plans.into_iter().zip(all_hits)
    {
        let (ia, ib) = (job.ia, job.ib);
        let (a, b) = (&bodies[ia], &bodies[ib]);
        let (Some(sa), Some(sb)) = (state.surfaces.get(&a.def.id), state.surfaces.get(&b.def.id))
        else {
            continue;
        };
        dt[ia] = dt[ia].min(limit);
        dt[ib] = dt[ib].min(limit);
        if !find {
            continue;
        }
        if segment_pass {
            let segs = |k: usize| given.counted_segments.get(k).map(Vec::as_slice);
            let counted = (segs(ia), segs(ib));
            let wanted = |k: usize| given.slave_segments.get(k).map(Vec::as_slice);
            let slaves = (wanted(ia), wanted(ib));
            let lists = state.seg_lists.entry((a.def.id, b.def.id)).or_default();
            let st = segment_pair(bodies, ia, ib, sa, sb, cfg, dt_ref, counted, slaves, lists);
            // the stiffening law's step (docs/theory-contact.md, "Depth")
            let (a, b) = (&bodies[ia], &bodies[ib]);
            let c = 0.5 * (a.def.section.thickness + b.def.section.thickness);
            if let Some(d) = stiffening::step(cfg.penalty_scale, st.max_penetration / c, pair_dt) {
                dt[ia] = dt[ia].min(d);
                dt[ib] = dt[ib].min(d);
            }
            state.stats.push(st);
            continue;
        }
        // nodal normals where the passes read them: the hit nodes and the corners of
        // their segments (stale values elsewhere are never read)
        for b_ in [a, b] {
            let buf = state.normals.entry(b_.def.id).or_default();
            buf.resize(b_.state.x.len(), Vec3::zeros());
        }
        for (hits, nb, sb_, surf_n, surf_s) in [(&hits_a, a, b, sa, sb), (&hits_b, b, a, sb, sa)] {
            for h in hits {
                if let Some(own) = state.normals.get_mut(&nb.def.id) {
                    own[h.node as usize] = surf_n.nodal_normal(h.node, &nb.state.x);
                }
                let seg = surf_s.segments[h.segment as usize];
                if let Some(other) = state.normals.get_mut(&sb_.def.id) {
                    for &n in seg.nodes() {
                        other[n as usize] = surf_s.nodal_normal(n, &sb_.state.x);
                    }
                }
            }
        }
        let empty = Vec::new();
        let na = state.normals.get(&a.def.id).unwrap_or(&empty);
        let nb_ = state.normals.get(&b.def.id).unwrap_or(&empty);
        let first = forces(
            &hits_a,
            a,
            b,
            sb,
            cfg,
            dt_ref,
            Normals {
                segment: nb_,
                node: na,
            },
        );
        let second = forces(
            &hits_b,
            b,
            a,
            sa,
            cfg,
            dt_ref,
            Normals {
                segment: na,
                node: nb_,
            },
        );
        let mut st = PairStats::empty(a.def.id, b.def.id, 0);
        let thin = a.def.section.thickness.min(b.def.section.thickness);
        let segs_b: Vec<Segment> = first
            .iter()
            .map(|p| sb.segments[p.hit.segment as usize])
            .collect();
        let segs_a: Vec<Segment> = second
            .iter()
            .map(|p| sa.segments[p.hit.segment as usize])
            .collect();
        let counted = |k: usize| given.counted.get(k).map(Vec::as_slice);
        apply(
            bodies,
            (ia, ib),
            &first,
            &segs_b,
            &mut st,
            true,
            counted(ia),
        );
        apply(
            bodies,
            (ib, ia),
            &second,
            &segs_a,
            &mut st,
            false,
            counted(ib),
        );
        st.kin_a.settle_nodes();
        st.kin_b.settle_nodes();
        st.settle(thin);
        state.stats.push(st);
    }
    Ok(dt)
}

/// Add the pushes of one pass (nodes of body `inode` on segments of `iseg`): +f on
/// the node, -w_k f on the segment nodes, sequentially in hit order; what lands on a
/// kinematic body goes into the pair's `KinLoad` too. The pair's statistics book the
/// pushes whose node `counted` holds (every push without it).
fn apply(
    bodies: &mut [Body],
    (inode, iseg): (usize, usize),
    pushes: &[Push],
    segs: &[Segment],
    st: &mut PairStats,
    node_body_is_a: bool,
    counted: Option<&[bool]>,
) {
    let (kin_node, kin_seg) = (bodies[inode].def.kinematic, bodies[iseg].def.kinematic);
    // the pair's loads so far (the first pass's), continued by this pass in hit order
    let (mut l_node, mut l_seg) = if node_body_is_a {
        (take(&mut st.kin_a), take(&mut st.kin_b))
    } else {
        (take(&mut st.kin_b), take(&mut st.kin_a))
    };
    for (p, seg) in pushes.iter().zip(segs) {
        let node = p.hit.node as usize;
        let bn = &mut bodies[inode];
        bn.state.f_contact[node] += p.force;
        if kin_node {
            l_node.push(p.hit.node, p.force, bn.state.v[node], bn.def.program[node]);
        }
        let b = &mut bodies[iseg];
        for (q, &n) in seg.nodes().iter().enumerate() {
            let f = p.force * p.weights[q];
            b.state.f_contact[n as usize] -= f;
            if kin_seg {
                l_seg.push(n, -f, b.state.v[n as usize], b.def.program[n as usize]);
            }
        }
        if counted.is_none_or(|c| c.get(node).copied().unwrap_or(false)) {
            st.active_nodes += 1;
            let on_a = (inode != iseg).then(|| if node_body_is_a { p.force } else { -p.force });
            st.book(p.hit.depth, p.normal_force, on_a);
        }
    }
    // (a kinematic body has no self pair: the seg side is the node side only there)
    if node_body_is_a {
        (st.kin_a, st.kin_b) = (l_node, l_seg);
    } else {
        (st.kin_b, st.kin_a) = (l_node, l_seg);
    }
}

/// The tunnelling guard: a contact body whose node moved farther in this step than its
/// per-step budget (half the search margin) stops the run. `moves[k]` is body k's
/// largest nodal displacement in the step and its node.
pub fn check_moves(
    bodies: &[Body],
    cfg: &ContactConfig,
    moves: &[(f64, usize)],
    h: f64,
    step: u64,
) -> Result<(), Fault> {
    if !cfg.enabled {
        return Ok(());
    }
    for (b, &(distance, node)) in bodies.iter().zip(moves) {
        let budget = cfg.step_budget(b);
        if b.def.contact && distance > budget {
            return Err(Fault::Tunnelling {
                step,
                body: b.def.id,
                node,
                speed: if h > 0.0 { distance / h } else { f64::INFINITY },
                distance,
                budget,
            });
        }
    }
    Ok(())
}
