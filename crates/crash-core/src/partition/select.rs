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

/// Element (or point) boxes tagged with their body's index in the group.
pub(super) type Boxes = RTree<GeomWithData<Rectangle<[f64; 3]>, u32>>;

/// What a view is selected against: every contact body's element boxes (`all`), the
/// holder's parts' element boxes (`mine`), the reach G and whether the ring is kept.
pub(super) struct Reach<'a> {
    pub all: &'a Boxes,
    pub mine: &'a Boxes,
    pub g: f64,
    pub ring: bool,
}

fn rect(lo: Vec3, hi: Vec3) -> Rectangle<[f64; 3]> {
    Rectangle::from_corners([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z])
}

/// Node boxes of the elements of some bodies (body index, body, element list) at their
/// current positions, in one R-tree.
pub(super) fn element_boxes<'a>(
    parts: impl Iterator<Item = (usize, &'a Body, &'a [u32])>,
) -> Boxes {
    let boxes = parts
        .flat_map(|(j, b, element)| {
            element.iter().map(move |&e| {
                let (lo, hi) = node_box(b, e as usize);
                GeomWithData::new(rect(lo, hi), j as u32)
            })
        })
        .collect();
    RTree::bulk_load(boxes)
}

/// Box of element e's nodes (triangles then quads) at the current positions.
fn node_box(b: &Body, e: usize) -> (Vec3, Vec3) {
    nodes_of(b, e)
        .iter()
        .fold(crate::mesh::bounds(&[]), |(lo, hi), &n| {
            let p = b.state.x[n as usize];
            (lo.inf(&p), hi.sup(&p))
        })
}

fn nodes_of(b: &Body, e: usize) -> &[u32] {
    let d = &b.def;
    let nt = d.tris.len();
    if e < nt {
        &d.tris[e].nodes
    } else {
        &d.quads[e - nt].nodes
    }
}

/// Does the box (lo, hi) grown by r meet a box of `tree` whose body passes `which`?
fn near(tree: &Boxes, (lo, hi): (Vec3, Vec3), r: f64, which: impl Fn(u32) -> bool) -> bool {
    let q = AABB::from_corners(
        [lo.x - r, lo.y - r, lo.z - r],
        [hi.x + r, hi.y + r, hi.z + r],
    );
    tree.locate_in_envelope_intersecting(&q)
        .any(|e| which(e.data))
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
            let other = |k: u32| k as usize != j;
            let own = |k: u32| k as usize == j;
            b.state
                .x
                .iter()
                .enumerate()
                .map(|(n, p)| {
                    let bx = (*p, *p);
                    (near(reach.all, bx, g, other)
                        && (owned(j, n as u32) || near(reach.mine, bx, g, other)))
                        || (b.def.self_contact && near(reach.mine, bx, g, own))
                })
                .collect()
        })
        .collect();
    let points: Boxes = RTree::bulk_load(
        bodies
            .iter()
            .zip(&slaves)
            .enumerate()
            .flat_map(|(j, (b, keep))| {
                keep.iter()
                    .zip(&b.state.x)
                    .filter(|(k, _)| **k)
                    .map(move |(_, p)| GeomWithData::new(rect(*p, *p), j as u32))
            })
            .collect(),
    );
    bodies
        .iter()
        .zip(slaves)
        .enumerate()
        .map(|(j, (b, mut keep))| {
            if !b.def.contact {
                return (Vec::new(), Vec::new());
            }
            let ne = b.def.element_count();
            // a slave's own segments too (its normal sums them), then the segments near
            // a slave of another body
            let mut take: Vec<bool> = (0..ne)
                .map(|e| {
                    let bx = node_box(b, e);
                    nodes_of(b, e).iter().any(|&n| keep[n as usize])
                        || near(&points, bx, g, |k| k as usize != j)
                        || (b.def.self_contact
                            && near(reach.mine, bx, 2.0 * g, |k| k as usize == j))
                })
                .collect();
            let corners = |keep: &mut Vec<bool>, take: &[bool]| {
                for e in (0..ne).filter(|&e| take[e]) {
                    for &n in nodes_of(b, e) {
                        keep[n as usize] = true;
                    }
                }
            };
            corners(&mut keep, &take);
            // the ring: every segment at a node of the view, so that each normal read
            // sums all of its node's segments
            if reach.ring {
                let core = keep.clone();
                for (e, t) in take.iter_mut().enumerate() {
                    if nodes_of(b, e).iter().any(|&n| core[n as usize]) {
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
        })
        .collect()
}
