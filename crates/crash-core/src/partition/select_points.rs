//! What a holder's contact view holds under the segment pass (`ContactPass::Segments`,
//! docs/theory-contact.md, "Segment pass"): the segments whose points can push one of
//! the holder's owned nodes, every master such a point can touch, and a ring around
//! them all, at the positions of a view build (`select` is the node passes' rule).
//!
//! A point of slave segment s pressed by master m pushes the corners of s and m and,
//! through the loads on their corner normals (`curved::normal_pullback`), every node of
//! the segments around those corners. So it pushes an owned node n only if s or m has
//! a corner that is n or a neighbour of n: s or m lies in the second ring of segments
//! around the holder's owned nodes (the segments with a node of one of the holder's
//! elements: a part holds every element of its owned nodes). A point of s touches m
//! only if their node boxes lie within c + bulge(s) + bulge(m) (its gap is d - h_m - c
//! and it stands off its facet by at most h_s); each bulge is at most its segment's
//! loose bound (`curved::loose_factor` times its node box's diagonal), and until the next build
//! every node moves at most the skin, so for bodies j and k G = c + L_j + L_k + 2 skin
//! (L_j body j's largest loose bound at the build, the diagonals grown by 2 sqrt(3)
//! skin) bounds that distance at the build. The view's slaves are the segments within
//! G of another body's segment that are in that second ring or within G of another
//! body's segment in it; its masters every segment of another body within G of a slave
//! (so each point's closest master is the whole body's); then the corners and one ring
//! of segments around every node (complete corner normals, and every node a pull-back
//! reaches).
//! Only the slaves are searched (`View::slave_segments`): a point of another segment
//! could find a wrong master or none, and its pushes would reach no owned node anyway.
//! The statistics book only the points of the segments the holder counts
//! (`View::counted_segments`).

use super::select::{corners_and_ring, node_box, nodes_of, Boxes};
use crate::body::Body;
use crate::contact::curved::loose_factor;

/// The segments' reach of a view build (module text), per pair of bodies.
pub(super) struct SegmentReach {
    /// Per body: its largest loose bulge bound, every node box grown by the skin (0
    /// for a body without contact), and its thickness.
    loose: Vec<f64>,
    thick: Vec<f64>,
    skin: f64,
}

impl SegmentReach {
    pub(super) fn of(bodies: &[Body], skin: f64) -> Self {
        let grow = 2.0 * 3f64.sqrt() * skin;
        let loose = bodies
            .iter()
            .map(|b| {
                if !b.def.contact {
                    return 0.0;
                }
                (0..b.def.element_count())
                    .map(|e| {
                        let (lo, hi) = node_box(b, e);
                        loose_factor(nodes_of(b, e).len()) * ((hi - lo).norm() + grow)
                    })
                    .fold(0.0, f64::max)
            })
            .collect();
        let thick = bodies.iter().map(|b| b.def.section.thickness).collect();
        Self { loose, thick, skin }
    }

    /// G of bodies j and k.
    fn g(&self, j: usize, k: usize) -> f64 {
        let c = 0.5 * (self.thick[j] + self.thick[k]);
        (c + self.loose[j] + self.loose[k] + 2.0 * self.skin) * (1.0 + 1e-9)
    }

    /// The largest G of body j with any body.
    fn most(&self, j: usize) -> f64 {
        (0..self.loose.len())
            .map(|k| self.g(j, k))
            .fold(0.0, f64::max)
    }
}

/// What `select_segments` picks: per body, the nodes and segments of the view and the
/// slaves among them (whole-body indices, sorted).
pub(super) type Picked = (Vec<(Vec<u32>, Vec<u32>)>, Vec<Vec<u32>>);

/// The nodes and segments of every body of `bodies` in the view under the segment
/// pass (empty for a body without contact), and its slaves. `mine[j]`: the holder's
/// elements of body j (None: none); `all`: every contact body's elements.
pub(super) fn select_segments(
    bodies: &[Body],
    mine: &[Option<Vec<u32>>],
    all: &Boxes,
    reach: &SegmentReach,
) -> Picked {
    // the second ring around the owned nodes: segments with a node of a holder element
    let ring2: Vec<Option<Vec<u32>>> = bodies
        .iter()
        .zip(mine)
        .map(|(b, m)| {
            let m = m.as_ref().filter(|_| b.def.contact)?;
            let mut near = vec![false; b.state.x.len()];
            for &e in m {
                for &n in nodes_of(b, e as usize) {
                    near[n as usize] = true;
                }
            }
            let ne = b.def.element_count() as u32;
            Some(
                (0..ne)
                    .filter(|&e| nodes_of(b, e as usize).iter().any(|&n| near[n as usize]))
                    .collect(),
            )
        })
        .collect();
    let ring2_boxes = Boxes::of_elements(bodies, &ring2);
    // the slaves: near another body, and in the ring or near another body's ring
    let slaves: Vec<Option<Vec<u32>>> = bodies
        .iter()
        .enumerate()
        .map(|(j, b)| {
            if !b.def.contact {
                return None;
            }
            let body_box = crate::mesh::bounds(&b.state.x);
            let others = |t: &Boxes| -> Vec<(usize, f64)> {
                t.near_bodies(body_box, reach.most(j))
                    .into_iter()
                    .filter(|&k| k != j)
                    .map(|k| (k, reach.g(j, k)))
                    .collect()
            };
            let (near_all, near_ring) = (others(all), others(&ring2_boxes));
            let mut in_ring = vec![false; b.def.element_count()];
            for &e in ring2[j].iter().flatten() {
                in_ring[e as usize] = true;
            }
            let ne = b.def.element_count() as u32;
            Some(
                (0..ne)
                    .filter(|&e| {
                        let bx = node_box(b, e as usize);
                        near_all.iter().any(|&(k, g)| all.near(k, bx, g))
                            && (in_ring[e as usize]
                                || near_ring.iter().any(|&(k, g)| ring2_boxes.near(k, bx, g)))
                    })
                    .collect(),
            )
        })
        .collect();
    let slave_boxes = Boxes::of_elements(bodies, &slaves);
    let picked = bodies
        .iter()
        .enumerate()
        .map(|(j, b)| {
            if !b.def.contact {
                return (Vec::new(), Vec::new());
            }
            let ne = b.def.element_count();
            let body_box = crate::mesh::bounds(&b.state.x);
            let others: Vec<(usize, f64)> = slave_boxes
                .near_bodies(body_box, reach.most(j))
                .into_iter()
                .filter(|&k| k != j)
                .map(|k| (k, reach.g(j, k)))
                .collect();
            let mut take = vec![false; ne];
            for &e in slaves[j].iter().flatten() {
                take[e as usize] = true;
            }
            // the masters of the other bodies' slaves
            for (e, t) in take.iter_mut().enumerate() {
                if !*t && !others.is_empty() {
                    let bx = node_box(b, e);
                    *t = others.iter().any(|&(k, g)| slave_boxes.near(k, bx, g));
                }
            }
            // their corners, then the ring: every segment at one of those nodes
            corners_and_ring(b, take, vec![false; b.state.x.len()], true)
        })
        .collect();
    (
        picked,
        slaves.into_iter().map(Option::unwrap_or_default).collect(),
    )
}

/// The union of two selections of the same bodies (sorted lists).
pub(super) fn union(
    a: Vec<(Vec<u32>, Vec<u32>)>,
    b: Vec<(Vec<u32>, Vec<u32>)>,
) -> Vec<(Vec<u32>, Vec<u32>)> {
    let merge = |mut x: Vec<u32>, y: Vec<u32>| {
        x.extend(y);
        x.sort_unstable();
        x.dedup();
        x
    };
    a.into_iter()
        .zip(b)
        .map(|((na, ea), (nb, eb))| (merge(na, nb), merge(ea, eb)))
        .collect()
}
