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
//! loose bound (pairs / 8 times its node box's diagonal), and until the next build
//! every node moves at most the skin, so G = t_max + 2 L + 2 skin (L the largest loose
//! bound at the build, the diagonals grown by 2 sqrt(3) skin) bounds that distance at
//! the build. The view's slaves are the segments within G of another body's segment
//! that are in that second ring or within G of another body's segment in it; its
//! masters every segment of another body within G of a slave (so each point's closest
//! master is the whole body's); then the corners and one ring of segments around every
//! node (complete corner normals, and every node a pull-back reaches).
//! A point of a segment outside those sets may find a wrong master or none, but its
//! pushes reach no owned node, and the statistics book only the points of the segments
//! the holder counts (`View::counted_segments`).

use super::select::{node_box, nodes_of, Boxes};
use crate::body::Body;

/// The segments' reach G of a view build (module text): the thickest contact body,
/// the largest loose bulge bound with every node box grown by the skin, two skins.
pub(super) fn segment_reach(bodies: &[Body], skin: f64) -> f64 {
    let grow = 2.0 * 3f64.sqrt() * skin;
    let mut t_max = 0.0f64;
    let mut loose = 0.0f64;
    for b in bodies.iter().filter(|b| b.def.contact) {
        t_max = t_max.max(b.def.section.thickness);
        for e in 0..b.def.element_count() {
            let (lo, hi) = node_box(b, e);
            let pairs = if nodes_of(b, e).len() == 3 { 3.0 } else { 6.0 };
            loose = loose.max(pairs / 8.0 * ((hi - lo).norm() + grow));
        }
    }
    (t_max + 2.0 * loose + 2.0 * skin) * (1.0 + 1e-9)
}

/// The nodes and segments (whole-body indices, sorted) of every body of `bodies` in
/// the view under the segment pass (empty for a body without contact). `mine[j]`: the
/// holder's elements of body j (None: none); `all`: every contact body's elements;
/// `g`: `segment_reach`.
pub(super) fn select_segments(
    bodies: &[Body],
    mine: &[Option<Vec<u32>>],
    all: &Boxes,
    g: f64,
) -> Vec<(Vec<u32>, Vec<u32>)> {
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
            let others = |t: &Boxes| -> Vec<usize> {
                t.near_bodies(body_box, g)
                    .into_iter()
                    .filter(|&k| k != j)
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
                        near_all.iter().any(|&k| all.near(k, bx, g))
                            && (in_ring[e as usize]
                                || near_ring.iter().any(|&k| ring2_boxes.near(k, bx, g)))
                    })
                    .collect(),
            )
        })
        .collect();
    let slave_boxes = Boxes::of_elements(bodies, &slaves);
    bodies
        .iter()
        .enumerate()
        .map(|(j, b)| {
            if !b.def.contact {
                return (Vec::new(), Vec::new());
            }
            let ne = b.def.element_count();
            let body_box = crate::mesh::bounds(&b.state.x);
            let others: Vec<usize> = slave_boxes
                .near_bodies(body_box, g)
                .into_iter()
                .filter(|&k| k != j)
                .collect();
            let mut take = vec![false; ne];
            for &e in slaves[j].iter().flatten() {
                take[e as usize] = true;
            }
            // the masters of the other bodies' slaves
            for (e, t) in take.iter_mut().enumerate() {
                if !*t && !others.is_empty() {
                    let bx = node_box(b, e);
                    *t = others.iter().any(|&k| slave_boxes.near(k, bx, g));
                }
            }
            // their corners, then the ring: every segment at one of those nodes
            let mut keep = vec![false; b.state.x.len()];
            let corners = |keep: &mut Vec<bool>, take: &[bool]| {
                for e in (0..ne).filter(|&e| take[e]) {
                    for &n in nodes_of(b, e) {
                        keep[n as usize] = true;
                    }
                }
            };
            corners(&mut keep, &take);
            for (e, t) in take.iter_mut().enumerate() {
                if nodes_of(b, e).iter().any(|&n| keep[n as usize]) {
                    *t = true;
                }
            }
            corners(&mut keep, &take);
            let node = (0..keep.len() as u32)
                .filter(|&n| keep[n as usize])
                .collect();
            let element = (0..ne as u32).filter(|&e| take[e as usize]).collect();
            (node, element)
        })
        .collect()
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
