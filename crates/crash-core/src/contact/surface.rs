//! Level ii of the search, per body: the body's segments in a bulk-loaded R-tree whose
//! boxes are inflated by half the thickness plus a Verlet skin. The tree is rebuilt only
//! when some node has moved farther than the skin since the last build; between builds
//! every segment still lies inside its stored box grown by its nodes' displacement, so
//! a query never misses a segment within the capture distance. A cache: the segments a
//! query returns are filtered by exact distance, so results never depend on it.

use super::segment::{segments, Segment};
use crate::body::Body;
use crate::Vec3;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

type Entry = GeomWithData<Rectangle<[f64; 3]>, u32>;

/// Search data of one body's contact surface.
#[derive(Debug, Clone)]
pub struct Surface {
    pub node_count: usize,
    pub segments: Vec<Segment>,
    /// Element-form stiffness per unit penalty scale: E/(1-nu^2) A0 / L0 (L0: longest
    /// edge of a triangle, longest diagonal of a quad), per segment.
    pub k_unit: Vec<f64>,
    /// Smallest node mass of each segment.
    pub seg_mass: Vec<f64>,
    /// min_j seg_mass_j / k_unit_j and min_j 1 / k_unit_j (element-form stable step).
    pub mass_per_k: f64,
    pub inv_k: f64,
    /// Smallest node mass of the body.
    pub min_mass: f64,
    /// Node adjacency (CSR) for self-contact exclusion.
    pub adj_start: Vec<u32>,
    pub adj: Vec<u32>,
    tree: RTree<Entry>,
    reference: Vec<Vec3>,
    skin: f64,
    built: bool,
    pub builds: u64,
}

fn node_adjacency(n: usize, segs: &[Segment]) -> (Vec<u32>, Vec<u32>) {
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n];
    for s in segs {
        for &a in s.nodes() {
            for &b in s.nodes() {
                if a != b {
                    lists[a as usize].push(b);
                }
            }
        }
    }
    let mut start = Vec::with_capacity(n + 1);
    let mut adj = Vec::new();
    start.push(0u32);
    for mut l in lists {
        l.sort_unstable();
        l.dedup();
        adj.extend(l);
        start.push(adj.len() as u32);
    }
    (start, adj)
}

impl Surface {
    pub fn new(body: &Body) -> Self {
        let segs = segments(body);
        let ep = body.def.section.material.plate_modulus();
        let x0 = &body.def.x0;
        let mut k_unit = Vec::with_capacity(segs.len());
        let mut seg_mass = Vec::with_capacity(segs.len());
        for s in &segs {
            let p: Vec<Vec3> = s.nodes().iter().map(|&n| x0[n as usize]).collect();
            let (area, len) = if s.count == 3 {
                let area = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
                let len = (0..3)
                    .map(|k| (p[(k + 1) % 3] - p[k]).norm())
                    .fold(0.0, f64::max);
                (area, len)
            } else {
                let area = 0.5 * (p[2] - p[0]).cross(&(p[3] - p[1])).norm();
                (area, (p[2] - p[0]).norm().max((p[3] - p[1]).norm()))
            };
            k_unit.push(ep * area / len);
            let m = s
                .nodes()
                .iter()
                .map(|&n| body.def.mass[n as usize])
                .fold(f64::INFINITY, f64::min);
            seg_mass.push(m);
        }
        let mass_per_k = seg_mass
            .iter()
            .zip(&k_unit)
            .map(|(m, k)| m / k)
            .fold(f64::INFINITY, f64::min);
        let inv_k = k_unit.iter().map(|k| 1.0 / k).fold(f64::INFINITY, f64::min);
        let (adj_start, adj) = node_adjacency(body.state.x.len(), &segs);
        Self {
            node_count: body.state.x.len(),
            segments: segs,
            k_unit,
            seg_mass,
            mass_per_k,
            inv_k,
            min_mass: body.def.mass.iter().copied().fold(f64::INFINITY, f64::min),
            adj_start,
            adj,
            tree: RTree::new(),
            reference: Vec::new(),
            skin: 0.0,
            built: false,
            builds: 0,
        }
    }

    /// Does this cache still describe `body` (same topology size)?
    pub fn fits(&self, body: &Body) -> bool {
        self.node_count == body.state.x.len() && self.segments.len() == body.element_count()
    }

    /// Rebuild the tree if it is missing, the skin changed or a node moved farther than
    /// the skin since the last build. Returns whether it rebuilt.
    pub fn refresh(&mut self, body: &Body, skin: f64) -> bool {
        let moved = || {
            let s2 = skin * skin;
            body.state.x.iter().zip(&self.reference).any(|(a, b)| {
                let d2 = (a - b).norm_squared();
                d2.is_nan() || d2 > s2
            })
        };
        if self.built && self.skin == skin && self.reference.len() == body.state.x.len() && !moved()
        {
            return false;
        }
        let pad = 0.5 * body.def.section.thickness + skin;
        let x = &body.state.x;
        let entries: Vec<Entry> = self
            .segments
            .iter()
            .enumerate()
            .map(|(j, s)| {
                let mut lo = Vec3::repeat(f64::INFINITY);
                let mut hi = Vec3::repeat(f64::NEG_INFINITY);
                for &n in s.nodes() {
                    lo = lo.inf(&x[n as usize]);
                    hi = hi.sup(&x[n as usize]);
                }
                let r = Rectangle::from_corners(
                    [lo.x - pad, lo.y - pad, lo.z - pad],
                    [hi.x + pad, hi.y + pad, hi.z + pad],
                );
                GeomWithData::new(r, j as u32)
            })
            .collect();
        self.tree = RTree::bulk_load(entries);
        self.reference.clear();
        self.reference.extend_from_slice(x);
        self.skin = skin;
        self.built = true;
        self.builds += 1;
        true
    }

    /// Segments whose stored box meets the cube of half-size `r` around `p`.
    pub fn candidates(&self, p: &Vec3, r: f64, out: &mut Vec<u32>) {
        out.clear();
        let q = AABB::from_corners([p.x - r, p.y - r, p.z - r], [p.x + r, p.y + r, p.z + r]);
        out.extend(
            self.tree
                .locate_in_envelope_intersecting(&q)
                .map(|e| e.data),
        );
    }

    /// Is segment `j` excluded from self-contact with node `i` (it holds the node or one
    /// of its neighbours)?
    pub fn near_in_topology(&self, i: u32, j: u32) -> bool {
        let nb =
            &self.adj[self.adj_start[i as usize] as usize..self.adj_start[i as usize + 1] as usize];
        self.segments[j as usize]
            .nodes()
            .iter()
            .any(|n| *n == i || nb.binary_search(n).is_ok())
    }
}
