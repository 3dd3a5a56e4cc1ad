//! Bodies that start inside each other: every pair of different contact bodies whose
//! boxes meet, measured the way the run's contact pass will measure it (nodes against
//! segments under the node passes; the segment pass's quadrature points on the curved
//! surfaces under it, which can reach into a body where no node does, e.g. a folded
//! part's crease bulging past its facets).

use super::config::{ContactConfig, ContactPass};
use super::narrow::{search, Hit};
use super::quadrature::PointPush;
use super::segpair::active_points;
use super::stage::{body_bounds, ensure_surface, pairs_of};
use super::surface::{node_chunks, Surface};
use super::verlet::NodeLists;
use crate::body::Body;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Where the deepest penetration of a (penetrating body, penetrated body) pass lies.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Inside {
    /// A node of the penetrating body (node passes).
    Node(usize),
    /// A quadrature point of the penetrating body's surface, on this element (segment
    /// pass).
    Point { element: usize },
}

impl Inside {
    /// What the count of a penetration counts.
    pub fn counted(&self) -> &'static str {
        match self {
            Inside::Node(_) => "node(s)",
            Inside::Point { .. } => "contact point(s) (segment pass, curved surface)",
        }
    }
}

impl std::fmt::Display for Inside {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Inside::Node(n) => write!(f, "node {n}"),
            Inside::Point { element } => write!(f, "a contact point on element {element}"),
        }
    }
}

/// A body that starts inside another body's contact surface.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Penetration {
    /// The penetrating body and the body whose segment it penetrates.
    pub node_body: u32,
    pub segment_body: u32,
    /// The deepest node or point of this (node body, segment body) pass, the segment
    /// it is inside and its depth [m] below the contact surface ((t_a + t_b)/2 from the
    /// mid-surface, the segment pass's curved surfaces where it runs).
    pub at: Inside,
    pub segment: usize,
    pub depth: f64,
    /// How many nodes (or points) of the node body penetrate that body.
    pub nodes: usize,
}

/// Initial penetrations between different bodies at the current positions, one entry
/// per (node body, segment body) with any, sorted by that pair.
pub fn initial_penetrations(bodies: &[Body], cfg: &ContactConfig) -> Vec<Penetration> {
    let mut out = Vec::new();
    let mut surfaces = BTreeMap::new();
    let bounds = body_bounds(bodies);
    for (ia, ib) in pairs_of(bodies, cfg, &bounds) {
        if ia == ib {
            continue;
        }
        for k in [ia, ib] {
            ensure_surface(
                &mut surfaces,
                &bodies[k],
                cfg.margin_for(&bodies[k]),
                None,
                None,
            );
        }
        let (a, b) = (&bodies[ia], &bodies[ib]);
        let (sa, sb) = (&surfaces[&a.def.id], &surfaces[&b.def.id]);
        let found = match cfg.pass {
            ContactPass::Nodes => [by_nodes(a, b, sb), by_nodes(b, a, sa)],
            ContactPass::Segments => {
                let [ab, ba] = active_points(a, sa, b, sb, cfg);
                [by_points(a, b, ab), by_points(b, a, ba)]
            }
        };
        out.extend(found.into_iter().flatten());
    }
    out.sort_by_key(|p| (p.node_body, p.segment_body));
    out
}

fn by_nodes(nb: &Body, sb: &Body, surf: &Surface) -> Option<Penetration> {
    let chunks = node_chunks(nb);
    let hits = search(nb, &chunks, sb, surf, false, &mut NodeLists::default());
    let deepest = hits.iter().fold(None::<&Hit>, |d, h| match d {
        Some(d) if d.depth >= h.depth => Some(d),
        _ => Some(h),
    })?;
    Some(Penetration {
        node_body: nb.def.id,
        segment_body: sb.def.id,
        at: Inside::Node(deepest.node as usize),
        segment: deepest.segment as usize,
        depth: deepest.depth,
        nodes: hits.len(),
    })
}

/// The deepest of a body's active points (`nb`'s against `sb`, their count) as a
/// penetration. Segments are the elements in element order (`segment::segments`), so a
/// segment's index names its element.
fn by_points(
    nb: &Body,
    sb: &Body,
    (count, deepest): (usize, Option<PointPush>),
) -> Option<Penetration> {
    let p = deepest?;
    Some(Penetration {
        node_body: nb.def.id,
        segment_body: sb.def.id,
        at: Inside::Point {
            element: p.slave_seg as usize,
        },
        segment: p.master_seg as usize,
        depth: p.depth,
        nodes: count,
    })
}
