//! What a holder's contact view holds: the nodes and segments of each contact body
//! that a hit touching one of the holder's owned nodes can read (the reach rule,
//! `contact`'s module text), at the positions of a view build.
//!
//! A hit pairs a slave node s of body A with a segment of another body B within
//! c = (t_A + t_B)/2 <= t_max of it; until the next build every node moves at most the
//! skin, so at the build they lie within G = t_max + 2 skin. A hit touches the holder
//! when s is owned here, or when its segment has an owned corner (then the segment is
//! an element of one of the holder's parts: a part holds every element of its owned
//! nodes). So the view's slaves are the nodes within G of an element of another
//! body and, of those, the ones owned here or within G of one of the holder's elements
//! of another body; its segments those within G of a slave of another body (each
//! slave's closest-segment choice is then the whole body's); then the corners of the
//! segments and one ring of segments around every view node (complete nodal normals;
//! a slave's own segments are always taken).
//! A body with self-contact also keeps, of itself, the nodes within G and the segments
//! within 2G of the holder's elements of it. A node in the view only as a corner or in
//! the ring never has a hit that touches an owned node: such a hit would make it a
//! slave by the rule above.
//!
//! Nodes far from every other body are left out: the sphere of the showcase lends its
//! views the cap near the plate only, not the half a part holds.

use crate::body::Body;
use crate::Vec3;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

/// Element (or point) boxes per body of the group (None: none of that body), each
/// body's in its own tree with the box around them all: a query for a body far from
/// a point ends at that box, and never walks the point's own body's elements (one tree
/// of every body tagged by body cost the floor scene's split 3 % of its run).
pub(super) struct Boxes {
    trees: Vec<Option<Tree>>,
}

/// Boxes per leaf of a body's tree: `CHUNK` consecutive boxes (elements or points in
/// index order, which meshes keep close in space) share one leaf box, and a query
/// tests the boxes of each leaf it meets. Why: a view build loads a tree of every
/// element of the group on every holder, and bulk-loading one leaf per element took
/// three quarters of a build (the showcase: 15 ms, 2.7 % of a split run's compute);
/// a leaf per 8 elements loads 8 times fewer. The answers are the same: a box meets
/// some element box exactly when it meets that element's leaf box and the box itself.
const CHUNK: usize = 8;

/// One body's boxes, its tree of leaf boxes (leaf k: boxes `CHUNK k..`) and the box
/// around them all.
struct Tree {
    boxes: Vec<(Vec3, Vec3)>,
    leaves: RTree<GeomWithData<Rectangle<[f64; 3]>, u32>>,
    env: (Vec3, Vec3),
}

impl Boxes {
    /// Node boxes of the elements `lists[j]` of each body j (None: none) at their
    /// current positions.
    pub(super) fn of_elements(bodies: &[Body], lists: &[Option<Vec<u32>>]) -> Self {
        let trees = bodies
            .iter()
            .zip(lists)
            .map(|(b, l)| {
                let l = l.as_ref().filter(|l| !l.is_empty())?;
                Some(Tree::of(
                    l.iter().map(|&e| node_box(b, e as usize)).collect(),
                ))
            })
            .collect();
        Self { trees }
    }

    /// The points of each body whose `keep` is set.
    fn of_points(bodies: &[Body], keep: &[Vec<bool>]) -> Self {
        let trees = bodies
            .iter()
            .zip(keep)
            .map(|(b, k)| {
                let boxes: Vec<(Vec3, Vec3)> = b
                    .state
                    .x
                    .iter()
                    .zip(k)
                    .filter(|(_, k)| **k)
                    .map(|(p, _)| (*p, *p))
                    .collect();
                (!boxes.is_empty()).then(|| Tree::of(boxes))
            })
            .collect();
        Self { trees }
    }

    /// The bodies with a box within r of (lo, hi) grown by `r` (those a query can meet).
    pub(super) fn near_bodies(&self, (lo, hi): (Vec3, Vec3), r: f64) -> Vec<usize> {
        let pad = Vec3::repeat(r);
        self.trees
            .iter()
            .enumerate()
            .filter_map(|(k, t)| meets((lo - pad, hi + pad), t.as_ref()?.env).then_some(k))
            .collect()
    }

    /// Does the box (lo, hi) grown by r meet a box of body k?
    pub(super) fn near(&self, k: usize, (lo, hi): (Vec3, Vec3), r: f64) -> bool {
        let Some(t) = self.trees.get(k).and_then(Option::as_ref) else {
            return false;
        };
        let pad = Vec3::repeat(r);
        let q = (lo - pad, hi + pad);
        if !meets(q, t.env) {
            return false;
        }
        let aabb = AABB::from_corners([q.0.x, q.0.y, q.0.z], [q.1.x, q.1.y, q.1.z]);
        t.leaves.locate_in_envelope_intersecting(&aabb).any(|leaf| {
            let first = leaf.data as usize * CHUNK;
            let last = (first + CHUNK).min(t.boxes.len());
            t.boxes[first..last].iter().any(|&b| meets(q, b))
        })
    }
}

impl Tree {
    fn of(boxes: Vec<(Vec3, Vec3)>) -> Self {
        let hull = |bs: &[(Vec3, Vec3)]| {
            bs.iter()
                .fold(crate::mesh::bounds(&[]), |(lo, hi), (l, h)| {
                    (lo.inf(l), hi.sup(h))
                })
        };
        let leaves = boxes
            .chunks(CHUNK)
            .enumerate()
            .map(|(k, c)| {
                let (lo, hi) = hull(c);
                GeomWithData::new(
                    Rectangle::from_corners([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]),
                    k as u32,
                )
            })
            .collect();
        Self {
            env: hull(&boxes),
            leaves: RTree::bulk_load(leaves),
            boxes,
        }
    }
}

fn meets((alo, ahi): (Vec3, Vec3), (blo, bhi): (Vec3, Vec3)) -> bool {
    (0..3).all(|d| alo[d] <= bhi[d] && blo[d] <= ahi[d])
}

/// What a view is selected against: every contact body's element boxes (`all`), the
/// holder's parts' element boxes (`mine`), the reach G and whether the ring is kept.
pub(super) struct Reach<'a> {
    pub all: &'a Boxes,
    pub mine: &'a Boxes,
    pub g: f64,
    pub ring: bool,
}

/// Box of element e's nodes (triangles then quads) at the current positions.
pub(super) fn node_box(b: &Body, e: usize) -> (Vec3, Vec3) {
    nodes_of(b, e)
        .iter()
        .fold(crate::mesh::bounds(&[]), |(lo, hi), &n| {
            let p = b.state.x[n as usize];
            (lo.inf(&p), hi.sup(&p))
        })
}

pub(super) fn nodes_of(b: &Body, e: usize) -> &[u32] {
    b.def.element_nodes(e)
}

/// The nodes and segments (whole-body indices, sorted) of every body of `bodies` in
/// the view (empty for a body without contact). `owned(j, n)`: node n of body j is
/// owned by one of the holder's parts.
pub(super) fn select(
    bodies: &[Body],
    owned: impl Fn(usize, u32) -> bool,
    reach: &Reach<'_>,
) -> Vec<(Vec<u32>, Vec<u32>)> {
    let g = reach.g;
    // the slaves of each body
    let slaves: Vec<Vec<bool>> = bodies
        .iter()
        .enumerate()
        .map(|(j, b)| {
            if !b.def.contact {
                return Vec::new();
            }
            let body_box = crate::mesh::bounds(&b.state.x);
            let others = |t: &Boxes| -> Vec<usize> {
                t.near_bodies(body_box, g)
                    .into_iter()
                    .filter(|&k| k != j)
                    .collect()
            };
            let (all, mine) = (others(reach.all), others(reach.mine));
            let itself = b.def.self_contact;
            if all.is_empty() && !itself {
                return vec![false; b.state.x.len()];
            }
            b.state
                .x
                .iter()
                .enumerate()
                .map(|(n, p)| {
                    let bx = (*p, *p);
                    let near = |t: &Boxes, ks: &[usize]| ks.iter().any(|&k| t.near(k, bx, g));
                    (near(reach.all, &all) && (owned(j, n as u32) || near(reach.mine, &mine)))
                        || (itself && reach.mine.near(j, bx, g))
                })
                .collect()
        })
        .collect();
    let points = Boxes::of_points(bodies, &slaves);
    bodies
        .iter()
        .zip(slaves)
        .enumerate()
        .map(|(j, (b, keep))| {
            if !b.def.contact {
                return (Vec::new(), Vec::new());
            }
            let ne = b.def.element_count();
            let body_box = crate::mesh::bounds(&b.state.x);
            let others: Vec<usize> = points
                .near_bodies(body_box, g)
                .into_iter()
                .filter(|&k| k != j)
                .collect();
            let itself = b.def.self_contact;
            // a slave's own segments too (its normal sums them), then the segments near
            // a slave of another body
            let take: Vec<bool> = (0..ne)
                .map(|e| {
                    if nodes_of(b, e).iter().any(|&n| keep[n as usize]) {
                        return true;
                    }
                    if others.is_empty() && !itself {
                        return false;
                    }
                    let bx = node_box(b, e);
                    others.iter().any(|&k| points.near(k, bx, g))
                        || (itself && reach.mine.near(j, bx, 2.0 * g))
                })
                .collect();
            corners_and_ring(b, take, keep, reach.ring)
        })
        .collect()
}

/// The view's lists of body `b` from the segments taken (`take`) and the nodes kept so
/// far (`keep`): the corners of the segments, then (`ring`) every segment at one of
/// those nodes, so that each normal read sums all of its node's segments, and their
/// corners; sorted whole-body indices (nodes, segments).
pub(super) fn corners_and_ring(
    b: &Body,
    mut take: Vec<bool>,
    mut keep: Vec<bool>,
    ring: bool,
) -> (Vec<u32>, Vec<u32>) {
    let ne = take.len();
    let corners = |keep: &mut Vec<bool>, take: &[bool]| {
        for e in (0..ne).filter(|&e| take[e]) {
            for &n in nodes_of(b, e) {
                keep[n as usize] = true;
            }
        }
    };
    corners(&mut keep, &take);
    if ring {
        for (e, t) in take.iter_mut().enumerate() {
            if !*t && nodes_of(b, e).iter().any(|&n| keep[n as usize]) {
                *t = true;
            }
        }
        corners(&mut keep, &take);
    }
    let node = (0..keep.len() as u32)
        .filter(|&n| keep[n as usize])
        .collect();
    let element = (0..ne as u32).filter(|&e| take[e as usize]).collect();
    (node, element)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A leaf per `CHUNK` boxes answers every query as a test of each box would: boxes
    /// scattered by a fixed sequence (so leaves of far-apart boxes overlap many
    /// queries), queries of every size, touching corners counted as meeting.
    #[test]
    fn leaves_of_chunked_boxes_answer_as_every_box_would() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut boxes = Vec::new();
        for _ in 0..203 {
            let lo = Vec3::new(next(), next(), next());
            let size = Vec3::new(next(), next(), next()) * 0.05;
            boxes.push((lo, lo + size));
        }
        let t = Tree::of(boxes.clone());
        let b = Boxes {
            trees: vec![None, Some(t)],
        };
        let (mut met, mut missed) = (0, 0);
        for k in 0..2000 {
            let p = Vec3::new(next(), next(), next());
            let r = 0.02 * next();
            // the corner of a box, exactly: a closed box meets it
            let p = if k % 10 == 0 {
                boxes[k % boxes.len()].1
            } else {
                p
            };
            let brute = boxes
                .iter()
                .any(|&bx| meets((p - Vec3::repeat(r), p + Vec3::repeat(r)), bx));
            assert_eq!(b.near(1, (p, p), r), brute, "query {k} at {p:?}, r {r}");
            assert!(!b.near(0, (p, p), r), "no boxes of body 0");
            if brute {
                met += 1;
            } else {
                missed += 1;
            }
        }
        assert!(
            met > 100 && missed > 100,
            "both answers tried: {met} / {missed}"
        );
    }
}
