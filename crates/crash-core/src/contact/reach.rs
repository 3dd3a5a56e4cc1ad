//! The search of the segment pass (`quadrature.rs`): which segments of a pair can
//! touch (the near sets), which master segments each slave segment sees, and each
//! point's master by the pass's rule (closest; ties within TIE c: the first in index
//! order), with culls that give that rule's answer. docs/theory-contact.md, "Segment
//! pass", "*Cost.*".

use super::curved::{loose_bulge_bound, near_curved, node_box, Curved, NearCurved};
use super::segment::{closest, point_gap2, Closest, Corners, Segment};
use super::surface::Surface;
use super::verlet::{box_list, NodeList};
use crate::Vec3;
use rayon::prelude::*;

/// Segments per task of a near set's node boxes.
const LIVE_TASK: usize = 256;

/// Euclidean gap of two boxes (0 when they meet).
pub(crate) fn box_gap(a: &(Vec3, Vec3), b: &(Vec3, Vec3)) -> f64 {
    box_gap2(a, b).sqrt()
}

/// Its square (`box_gap` is its correctly rounded root, the bits of `Vec3::norm`).
pub(crate) fn box_gap2(a: &(Vec3, Vec3), b: &(Vec3, Vec3)) -> f64 {
    ((b.0 - a.1).sup(&Vec3::zeros()) + (a.0 - b.1).sup(&Vec3::zeros())).norm_squared()
}

/// The segments of `surf` whose stored box comes within `grow` of the box `near` (per
/// axis), ascending, and their node boxes: from the query's `list`, kept from pass to
/// pass while the query stays inside it and the tree is the same build
/// (`verlet::box_list`, the tree's own test: the same set), so a pass costs what lies
/// near the other body, not the whole body.
fn live_boxes(
    surf: &Surface,
    x: &[Vec3],
    near: &(Vec3, Vec3),
    grow: f64,
    list: &mut NodeList,
) -> (Vec<u32>, Vec<(Vec3, Vec3)>) {
    let (lo, hi) = (near.0.add_scalar(-grow), near.1.add_scalar(grow));
    let mut live = Vec::new();
    box_list(
        list,
        surf,
        (&[lo.x, lo.y, lo.z], &[hi.x, hi.y, hi.z]),
        &mut live,
    );
    let boxes = live
        .par_iter()
        .with_min_len(LIVE_TASK)
        .map(|&j| node_box(&surf.segments[j as usize], x))
        .collect();
    (live, boxes)
}

/// `box_gap >= r` from the squared gap `s` (`box_gap2`) and r2 = r r: without the
/// square root where `s` is clearly on one side (sqrt is correctly rounded, so a
/// relative margin of 1e-12 on the squares decides it), the same answer always.
pub(crate) fn gap_at_least(s: f64, r: f64, r2: f64) -> bool {
    if s > r2 * (1.0 + 1e-12) {
        true
    } else if s < r2 * (1.0 - 1e-12) {
        false
    } else {
        s.sqrt() >= r
    }
}

/// The union of boxes (empty: inverted, infinitely far from everything).
pub(crate) fn union(boxes: &[(Vec3, Vec3)]) -> (Vec3, Vec3) {
    boxes.iter().fold(
        (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY)),
        |(lo, hi), b| (lo.inf(&b.0), hi.sup(&b.1)),
    )
}

/// The segments of both bodies of a pair that can touch the other (their curved data,
/// node boxes and largest bulge bound, `NearCurved`), in three steps so that the loose
/// bulge bound of a coarse flat body (a 6.7 mm plate quad: 1.8 mm, its true bulge 0) does
/// not size the other body's set:
/// - first body `p` (the one with the larger loose bound, `Surface::loose_bulge_ub`):
///   its segments within 1.25 c + both loose bounds of the other's (as before);
/// - then body `q`: its segments within 1.25 c + p's exact bound + q's loose bound of
///   the box of p's set;
/// - last, p's set kept to the segments within 1.25 c + q's exact bound + p's loose
///   bound of the box of q's set.
///
/// A point on segment s touches segment m only if their node boxes are nearer than c +
/// bulge(s) + bulge(m) (its gap is d - h_m - c with d >= that distance - h_s), and every
/// bulge is at most its segment's loose bound; so each step keeps every segment that can
/// touch one of the other's, and each exact bound (a max over a set holding every
/// segment that can touch) bounds the bulge of every segment a point can touch.
/// `lists`: the queries' kept lists, a's and b's first round, a's and b's second
/// (`verlet::PairLists::near`). Returns (a's, b's).
pub(crate) fn near_sets(
    (sa, xa): (&Surface, &[Vec3]),
    (sb, xb): (&Surface, &[Vec3]),
    base: f64,
    lists: &mut [NodeList; 4],
) -> (NearCurved, NearCurved) {
    let flip = sb.loose_bulge_ub > sa.loose_bulge_ub;
    let [a1, b1, a2, b2] = lists;
    let ((sp, xp), (sq, xq), (p1, q1, q2)) = if flip {
        ((sb, xb), (sa, xa), (b1, a1, a2))
    } else {
        ((sa, xa), (sb, xb), (a1, b1, b2))
    };
    let bounds = |s: &Surface| s.bounds();
    // 1. as before this step: every segment within the loose reach of the other body
    let live1 = base + sp.loose_bulge_ub + sq.loose_bulge_ub;
    let ((live_p, boxes_p), (live_q, boxes_q)) = rayon::join(
        || live_boxes(sp, xp, &bounds(sq), live1, p1),
        || live_boxes(sq, xq, &bounds(sp), live1, q1),
    );
    let grow1 =
        base + loose_bulge_bound(sp, &live_p, &boxes_p) + loose_bulge_bound(sq, &live_q, &boxes_q);
    let cp = near_curved(sp, xp, &live_p, &boxes_p, &union(&boxes_q), grow1);
    // 2. q's segments against p's set, with p's exact bound
    let box_p = union(cp.boxes());
    let live2 = base + cp.bound + sq.loose_bulge_ub;
    let (live_q, boxes_q) = live_boxes(sq, xq, &box_p, live2, q2);
    let grow2 = base + cp.bound + loose_bulge_bound(sq, &live_q, &boxes_q);
    let cq = near_curved(sq, xq, &live_q, &boxes_q, &box_p, grow2);
    // 3. p's set against q's, with q's exact bound
    let grow3 = base + cq.bound + loose_bulge_bound(sp, cp.segs(), cp.boxes());
    let cp = cp.within(&union(cq.boxes()), grow3);
    if flip {
        (cq, cp)
    } else {
        (cp, cq)
    }
}

/// A facet's unit normal and the span of its corners along it: every point of the flat
/// facet lies in that slab, so a point's distance to the facet is at least its distance
/// to the slab, less `margin` (round-off of the dot products and of the projection's
/// closest point, which `segment::closest` builds from weights within round-off of [0,
/// 1] on a facet that is not degenerate).
#[derive(Clone, Copy)]
pub(crate) struct Slab {
    n: Vec3,
    lo: f64,
    hi: f64,
    margin: f64,
}

impl Slab {
    /// The slab of a facet (a quad: its four sub-triangles around the centroid), or
    /// None when a (sub-)triangle is nearly degenerate (sine of its shape under 1e-3:
    /// the projection's weights there are not bounded by round-off).
    pub(crate) fn of(at: &Corners, scale: f64, c: f64) -> Option<Slab> {
        let xs = &at.xs;
        let k = at.count as usize;
        let l2 = (0..k)
            .map(|i| (xs[(i + 1) % k] - xs[i]).norm_squared())
            .fold(0.0, f64::max);
        let shaped = |a: &Vec3, b: &Vec3, c_: &Vec3| {
            let e = [
                (b - a).norm_squared(),
                (c_ - b).norm_squared(),
                (a - c_).norm_squared(),
            ];
            let m = e.iter().copied().fold(0.0, f64::max);
            (b - a).cross(&(c_ - a)).norm_squared() >= 1e-6 * m * m
        };
        let f = if k == 3 {
            if !shaped(&xs[0], &xs[1], &xs[2]) {
                return None;
            }
            (xs[1] - xs[0]).cross(&(xs[2] - xs[0]))
        } else {
            let ce = at.centroid;
            if !(0..4).all(|s| shaped(&ce, &xs[s], &xs[(s + 1) % 4])) {
                return None;
            }
            (xs[2] - xs[0]).cross(&(xs[3] - xs[1]))
        };
        let l = f.norm();
        if !(l > 0.0 && l.is_finite()) {
            return None;
        }
        let n = f / l;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for x in &xs[..k] {
            let s = n.dot(x);
            lo = lo.min(s);
            hi = hi.max(s);
        }
        let margin = 1e-8 * (c + l2.sqrt()) + 1e-12 * scale;
        lo.is_finite().then_some(Slab { n, lo, hi, margin })
    }

    /// A lower bound on the distance of the facet to points whose values along the
    /// normal lie in [a, b].
    fn gap_span(&self, a: f64, b: f64) -> f64 {
        (self.lo - b).max(a - self.hi) - self.margin
    }

    /// A lower bound on the distance of the facet to `p`.
    pub(crate) fn gap(&self, p: &Vec3) -> f64 {
        let s = self.n.dot(p);
        self.gap_span(s, s)
    }

    /// A lower bound on the distance of the facet to every point within `h` of the
    /// convex hull of `corners`.
    pub(crate) fn gap_hull(&self, corners: &[Vec3], h: f64) -> f64 {
        let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
        for x in corners {
            let s = self.n.dot(x);
            a = a.min(s);
            b = b.max(s);
        }
        self.gap_span(a - h, b + h)
    }
}

/// The master data of one candidate segment: its index, node box, corners, slab and
/// where its curved data are (an index, not a copy: the data are 232 bytes).
#[derive(Clone, Copy)]
pub(crate) struct Master {
    pub j: u32,
    pub bx: (Vec3, Vec3),
    pub at: Corners,
    pub cv: CurvedAt,
    pub slab: Option<Slab>,
}

impl Master {
    /// A lower bound on the distance of the facet to `p` (-inf without a slab).
    fn slab_gap(&self, p: &Vec3) -> f64 {
        self.slab.map_or(f64::NEG_INFINITY, |s| s.gap(p))
    }
}

/// Where a master's curved data are: in the pass's near set, or computed for this slave
/// segment (a segment outside the near set; the same values either way).
#[derive(Clone, Copy)]
pub(crate) enum CurvedAt {
    Near(usize),
    Extra(usize),
}

/// The master body's curved data as the point loop reads them.
pub(crate) struct MasterCurved<'a> {
    pub near: &'a NearCurved,
    pub extra: &'a [Curved],
}

impl MasterCurved<'_> {
    pub(crate) fn of(&self, m: &Master) -> &Curved {
        match m.cv {
            CurvedAt::Near(k) => self.near.at(k),
            CurvedAt::Extra(k) => &self.extra[k],
        }
    }
}

/// The rule itself, as the pass always ran it: over the masters `near` (index order)
/// those whose node box lies within `reach` of the point are its candidates; the first
/// is the best, a later one replaces it only when closer by more than `tie`. A
/// candidate whose box is farther than the closest distance so far plus `tie` is not
/// projected (it could neither replace the best nor lower that distance).
fn by_rule(
    xa: &Vec3,
    masters: &[Master],
    near: &[usize],
    reach: f64,
    tie: f64,
) -> Option<(Closest, usize)> {
    let mut best: Option<(Closest, usize)> = None;
    let mut dmin = f64::INFINITY;
    for &mi in near {
        let m = &masters[mi];
        let lb = box_gap(&(*xa, *xa), &m.bx);
        if lb >= reach || lb > dmin + tie {
            continue;
        }
        let pr = closest(xa, &m.at);
        if pr.dist.is_nan() {
            continue;
        }
        let better = match &best {
            None => true,
            Some((b, _)) => pr.dist < b.dist - tie,
        };
        dmin = dmin.min(pr.dist);
        if better {
            best = Some((pr, mi));
        }
    }
    best
}

/// How far the pass looks for a point's master: `reach`, the rule's (a master whose
/// node box lies within it of the point is a candidate), and `touch` <= reach, beyond
/// which no candidate can press on the point (its gap d - s h_m - c is >= 0 when d >=
/// c + the master's bulge bound, `quadrature::point_pushes`); `tie`, the rule's tie.
#[derive(Clone, Copy)]
pub(crate) struct Reach {
    pub reach: f64,
    pub touch: f64,
    pub tie: f64,
}

/// What `nearest` found for a point.
pub(crate) enum Pick {
    /// The rule's master (its projection, its position in the masters).
    Found(Closest, usize),
    /// No master can press on the point.
    Drop,
    /// Undecided by the masters within touch: run the rule again (`rule_again`).
    Rerun,
}

/// The point's master by the rule, when it lies within `touch` (`Pick::Drop` otherwise,
/// where the pass drops the point either way: its gap is >= 0). `masters` holds every
/// candidate of the rule whose node box lies within touch plus the slave's bulge bound
/// of the slave segment's node box (a point lies within that bound of it), so the
/// rule's other candidates lie at touch or beyond. `keep` is the masters less those
/// whose box or slab puts every point of the strip at or beyond `touch`; the point
/// skips those and the ones its own slab or box puts there too (with the rule's others,
/// the set F), and projects the rest (K) by the rule. That gives the rule's answer
/// wherever the pass uses it:
/// - a candidate of F (distance >= touch) changes the rule's best only by becoming it;
///   once a point of K is closer than every earlier candidate and touch by more than
///   `tie` ("caught up"), it is the best in both runs, the best stays below touch and no
///   candidate of F can replace it, so both runs end alike;
/// - if no candidate of K comes within touch, none does: the rule's best lies at touch
///   or beyond and the pass drops the point either way;
/// - otherwise (a candidate within touch but within `tie` of an earlier one or of
///   touch, never seen on the showcase) the rule runs over every candidate again
///   (`Pick::Rerun`; forcing it at every point gives the showcase's hash too).
///
/// A candidate skipped for its box or slab lying beyond the closest distance so far plus
/// `tie` is one the rule would not take either.
pub(crate) fn nearest(xa: &Vec3, masters: &[Master], keep: &[usize], r: Reach) -> Pick {
    let Reach { touch, tie, .. } = r;
    let mut best: Option<(Closest, usize)> = None;
    let mut dmin = f64::INFINITY;
    let mut caught_up = false;
    let touch2 = touch * touch;
    for &mi in keep {
        let m = &masters[mi];
        let sg = m.slab_gap(xa);
        if sg >= touch {
            continue;
        }
        // the rule's tests on the box gap, squared where that decides them (the second
        // one only skips a candidate the rule could not take, so erring towards
        // projecting costs time, not bits)
        let s = point_gap2(xa, &m.bx);
        if gap_at_least(s, touch, touch2) || sg > dmin + tie {
            continue;
        }
        let dt = dmin + tie;
        if s > dt * dt * (1.0 + 1e-12) {
            continue;
        }
        let pr = closest(xa, &m.at);
        if pr.dist.is_nan() {
            continue;
        }
        if !caught_up && pr.dist < dmin.min(touch) - tie {
            caught_up = true;
        }
        let better = match &best {
            None => true,
            Some((b, _)) => pr.dist < b.dist - tie,
        };
        dmin = dmin.min(pr.dist);
        if better {
            best = Some((pr, mi));
        }
    }
    match best {
        Some((pr, mi)) if caught_up => Pick::Found(pr, mi),
        // dmin is never NaN: it starts infinite and takes only distances that are not
        _ if dmin >= touch => Pick::Drop,
        _ => Pick::Rerun,
    }
}

/// What the rule's candidate list for a slave segment is made from: the master body,
/// its near set's curved data, the slave segment's node box, the tree query's growth of
/// it, the node-box reach beyond which a master is no candidate, and the coordinates'
/// size for the slabs.
pub(crate) struct Wide<'a> {
    pub msurf: &'a crate::contact::surface::Surface,
    pub xm: &'a [Vec3],
    pub mcurv: &'a NearCurved,
    pub sbx: (Vec3, Vec3),
    pub grow: f64,
    pub box_reach: f64,
    pub scale: f64,
    pub c: f64,
}

/// The rule over every candidate of the point `xa` (strip box `strip`) as the pass
/// always made them (the tree's segments whose stored box meets the slave's node box
/// grown by `grow`, in index order, less those whose node box lies at `box_reach` or
/// beyond, then those within `reach` of the strip's box): the master, its data and its
/// curved data, when it lies within reach.
pub(crate) fn rule_again(
    xa: &Vec3,
    strip: &(Vec3, Vec3),
    w: &Wide,
    r: Reach,
) -> Option<(Closest, Master, Curved)> {
    let (lo, hi) = (w.sbx.0.add_scalar(-w.grow), w.sbx.1.add_scalar(w.grow));
    let mut cand = Vec::new();
    w.msurf
        .query([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z], &mut cand);
    cand.sort_unstable();
    let br2 = w.box_reach * w.box_reach;
    let mut masters = Vec::new();
    let mut curved = Vec::new();
    for &j in &cand {
        let ms: &Segment = &w.msurf.segments[j as usize];
        let bx = node_box(ms, w.xm);
        if gap_at_least(box_gap2(&w.sbx, &bx), w.box_reach, br2) {
            continue;
        }
        let at = Corners::of(ms, w.xm);
        curved.push(match w.mcurv.index(j) {
            Some(k) => *w.mcurv.at(k),
            None => Curved::of(ms, w.msurf, w.xm),
        });
        masters.push(Master {
            j,
            bx,
            at,
            cv: CurvedAt::Extra(curved.len() - 1),
            slab: Slab::of(&at, w.scale, w.c),
        });
    }
    let reach2 = r.reach * r.reach;
    let near: Vec<usize> = (0..masters.len())
        .filter(|&mi| !gap_at_least(box_gap2(strip, &masters[mi].bx), r.reach, reach2))
        .collect();
    by_rule(xa, &masters, &near, r.reach, r.tie)
        .filter(|(pr, _)| pr.dist < r.reach)
        .map(|(pr, mi)| (pr, masters[mi], curved[mi]))
}
