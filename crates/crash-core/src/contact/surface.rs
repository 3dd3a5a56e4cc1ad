//! Level ii of the search, per body: the body's segments in bulk-loaded R-trees
//! (`forest.rs`, a few spatial groups built on the pool) whose boxes are inflated by
//! half the thickness plus a Verlet skin. The trees are rebuilt only when some node has
//! moved farther than the skin since the last build; between builds every segment still
//! lies inside its stored box grown by its nodes' displacement, so a query never misses
//! a segment within the capture distance. A cache: the segments a query returns are
//! filtered by exact distance, so results never depend on it.

use super::figures::NodeFigures;
use super::forest::{Entry, Forest};
use super::segment::{segments, Segment};
use crate::body::{Body, SurfaceFigures};
use crate::Vec3;
use rayon::prelude::*;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::RTreeObject;
use std::sync::atomic::{AtomicU64, Ordering};

/// Ids of the trees built in this process (`Surface::tree_id`).
static NEXT_TREE: AtomicU64 = AtomicU64::new(0);

/// Segments per task of a tree build's box pass.
const SEG_CHUNK: usize = 2048;

/// Nodes per task of the node passes (fixed: results are concatenated in node order).
pub const NODE_CHUNK: usize = 512;

/// The box and the largest speed of one chunk of a body's nodes at the current pass:
/// a node pass skips a chunk whose box cannot meet the other body (the test each node
/// would fail, made once per chunk), so its cost follows the contact zone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeChunk {
    pub lo: Vec3,
    pub hi: Vec3,
    /// max |v| over the chunk's nodes [m/s].
    pub vmax: f64,
}

impl NodeChunk {
    /// Does the chunk's box, grown by `grow`, meet the box (lo, hi)?
    pub fn meets(&self, lo: &Vec3, hi: &Vec3, grow: f64) -> bool {
        (0..3).all(|d| self.hi[d] >= lo[d] - grow && self.lo[d] <= hi[d] + grow)
    }
}

/// Chunk boxes and speeds of a body's nodes (min, max: the same bits in any order).
pub fn node_chunks(body: &Body) -> Vec<NodeChunk> {
    node_chunks_moved(body, &[], 0.0).0
}

/// `node_chunks`, and in the same read of the nodes whether one lies farther than
/// `skin` from its position in `reference` (a yes/no: the same answer in any order; an
/// empty or shorter reference says nothing) and the largest such distance (a bound for
/// the next steps' checks, `Surface::refresh_given`). One pass over x, v and the
/// reference instead of two: each pass over a large body costs a stream of its nodes.
pub fn node_chunks_moved(
    body: &Body,
    reference: &[Vec3],
    skin: f64,
) -> (Vec<NodeChunk>, bool, f64) {
    let x = &body.state.x;
    let check = reference.len() == x.len();
    let out: Vec<(NodeChunk, (bool, f64))> = x
        .par_chunks(NODE_CHUNK)
        .zip(body.state.v.par_chunks(NODE_CHUNK))
        .enumerate()
        .with_max_len(1)
        .map(|(k, (xs, vs))| {
            let (lo, hi) = crate::mesh::bounds(xs);
            let vmax = vs.iter().map(|v| v.norm()).fold(0.0, f64::max);
            let moved = if check {
                farthest(xs, &reference[k * NODE_CHUNK..], skin)
            } else {
                (false, 0.0)
            };
            (NodeChunk { lo, hi, vmax }, moved)
        })
        .collect();
    let moved = out.iter().any(|c| c.1 .0);
    let far = out.iter().map(|c| c.1 .1).fold(0.0, f64::max);
    (out.into_iter().map(|c| c.0).collect(), moved, far)
}

/// Whether a node of `x` lies farther than `skin` from its place in `reference` (or at
/// a NaN distance), and the largest distance.
fn farthest(x: &[Vec3], reference: &[Vec3], skin: f64) -> (bool, f64) {
    let s2 = skin * skin;
    let (nan, d2) = x
        .iter()
        .zip(reference)
        .fold((false, 0.0f64), |(nan, m), (a, b)| {
            let d2 = (a - b).norm_squared();
            (nan || d2.is_nan(), m.max(d2))
        });
    (nan || d2 > s2, d2.sqrt())
}

/// Fraction of the skin below which a bound on the nodes' distances from the last build
/// settles the skin check without reading the nodes: far above the rounding of the
/// distances and of the bound.
const DRIFT_SAFE: f64 = 0.999;

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
    /// The whole body's areal mass and mean segment area (the segment pass's stiffness
    /// and slave side).
    pub figures: SurfaceFigures,
    /// Node adjacency (CSR) for self-contact exclusion.
    pub adj_start: Vec<u32>,
    pub adj: Vec<u32>,
    /// Segments incident to each node (CSR), in the summation order of
    /// `smooth::nodal_normals`: triangles before quads, then corner slot, then segment.
    inc_start: Vec<u32>,
    inc: Vec<u32>,
    /// Chunk boxes and speeds of the body's nodes at the current pass (idem).
    pub chunks: Vec<NodeChunk>,
    tree: Forest,
    /// Each segment's stored box (the tree's entries, by segment index).
    boxes: Vec<([f64; 3], [f64; 3])>,
    /// Until the next build, a bound on `curved::loose_bulge_bound` of any segments'
    /// node boxes: `curved::loose_factor` x the largest stored box's diagonal without the
    /// half-thickness pads (a node box stays within its build's box grown by the skin).
    pub loose_bulge_ub: f64,
    /// `tree_id()`.
    tree_id: u64,
    reference: Vec<Vec3>,
    skin: f64,
    built: bool,
    pub builds: u64,
    /// A bound on every node's distance from `reference`, as of the pass of step
    /// `seen`.
    drift: f64,
    seen: Option<u64>,
}

fn node_incidence(n: usize, segs: &[Segment]) -> (Vec<u32>, Vec<u32>) {
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n];
    for count in [3u8, 4] {
        for k in 0..count as usize {
            for (j, s) in segs.iter().enumerate().filter(|(_, s)| s.count == count) {
                lists[s.nodes[k] as usize].push(j as u32);
            }
        }
    }
    let mut start = Vec::with_capacity(n + 1);
    start.push(0u32);
    let mut inc = Vec::new();
    for l in lists {
        inc.extend(l);
        start.push(inc.len() as u32);
    }
    (start, inc)
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

/// Twice the area times the unit normal of a segment: (x2 - x1) x (x3 - x1) for a
/// triangle, (x3 - x1) x (x4 - x2) for a quad.
pub fn face_vector(s: &Segment, x: &[Vec3]) -> Vec3 {
    let [a, b, c, d] = s.nodes.map(|i| x[i as usize]);
    if s.count == 3 {
        (b - a).cross(&(c - a))
    } else {
        (c - a).cross(&(d - b))
    }
}

impl Surface {
    pub fn new(body: &Body) -> Self {
        let segs = segments(body);
        let ep = body.def.section.material.plate_modulus();
        let x0 = &body.def.x0;
        let mut k_unit = Vec::with_capacity(segs.len());
        let mut seg_mass = Vec::with_capacity(segs.len());
        let mut total_area = 0.0;
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
            total_area += area;
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
        let (inc_start, inc) = node_incidence(body.state.x.len(), &segs);
        let mean_area = total_area / segs.len().max(1) as f64;
        Self {
            node_count: body.state.x.len(),
            segments: segs,
            k_unit,
            seg_mass,
            mass_per_k,
            inv_k,
            min_mass: body.def.mass.iter().copied().fold(f64::INFINITY, f64::min),
            figures: body.def.whole_surface.unwrap_or(SurfaceFigures {
                areal_mass: if total_area > 0.0 {
                    body.def.mass.iter().sum::<f64>() / total_area
                } else {
                    0.0
                },
                mean_area,
            }),
            adj_start,
            adj,
            inc_start,
            inc,
            chunks: node_chunks(body),
            tree: Forest::default(),
            boxes: Vec::new(),
            loose_bulge_ub: f64::INFINITY,
            tree_id: u64::MAX - 1,
            reference: Vec::new(),
            skin: 0.0,
            built: false,
            builds: 0,
            drift: f64::INFINITY,
            seen: None,
        }
    }

    /// Does this cache still describe `body` (same topology size)?
    pub fn fits(&self, body: &Body) -> bool {
        self.node_count == body.state.x.len() && self.segments.len() == body.element_count()
    }

    /// Rebuild the tree if it is missing, the skin changed or a node moved farther than
    /// the skin since the last build; the node chunks of this pass come with the answer
    /// (`node_chunks_moved` against `self.reference`: the nodes are read once for both).
    /// Returns whether it rebuilt.
    pub fn refresh(&mut self, body: &Body, skin: f64) -> bool {
        self.refresh_given(body, skin, None, None)
    }

    /// `refresh` for the pass of step `step`, with the figures the integration took of
    /// the nodes in the step that led here (`given`, the same bits): the node chunks
    /// come from them, and the skin check reads the nodes only when the bound on their
    /// distance from the last build (the distance found at the last read plus every
    /// step's largest move since) could reach the skin. The bound needs one step
    /// between this pass and the last (`seen`); otherwise the nodes are read.
    pub fn refresh_given(
        &mut self,
        body: &Body,
        skin: f64,
        given: Option<&NodeFigures>,
        step: Option<u64>,
    ) -> bool {
        let follows = step.is_some() && self.seen.is_some() && step == self.seen.map(|s| s + 1);
        self.seen = step;
        let current = self.current(body, skin);
        let moved = match given {
            Some(f) if follows && current => {
                self.chunks.clone_from(&f.chunks);
                let bound = self.drift + f.max_move;
                if bound <= DRIFT_SAFE * skin {
                    self.drift = bound;
                    false
                } else {
                    let (moved, far) = farthest(&body.state.x, &self.reference, skin);
                    self.drift = far;
                    moved
                }
            }
            _ => {
                let (chunks, moved, far) = node_chunks_moved(body, &self.reference, skin);
                self.chunks = chunks;
                self.drift = far;
                moved
            }
        };
        if current && !moved {
            return false;
        }
        self.rebuild(body, skin)
    }

    /// Built, for this skin and this many nodes.
    fn current(&self, body: &Body, skin: f64) -> bool {
        self.built && self.skin == skin && self.reference.len() == body.state.x.len()
    }

    /// Build the trees on the pool: boxes by segment chunks, then `Forest::build`.
    fn rebuild(&mut self, body: &Body, skin: f64) -> bool {
        let pad = 0.5 * body.def.section.thickness + skin;
        let x = &body.state.x;
        let entries: Vec<Entry> = self
            .segments
            .par_iter()
            .with_min_len(SEG_CHUNK)
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
        self.boxes = entries
            .par_iter()
            .with_min_len(SEG_CHUNK)
            .map(|e| {
                let env = e.geom().envelope();
                (env.lower(), env.upper())
            })
            .collect();
        // the pads less a hair, so round-off cannot make the bound too small
        let t = body.def.section.thickness * (1.0 - 1e-9);
        self.loose_bulge_ub = self
            .segments
            .iter()
            .zip(&self.boxes)
            .map(|(seg, (lo, hi))| {
                let f = super::curved::loose_factor(seg.count as usize);
                let d2: f64 = (0..3).map(|d| (hi[d] - lo[d] - t).max(0.0).powi(2)).sum();
                d2 * (f * f)
            })
            .fold(0.0, f64::max)
            .sqrt()
            * (1.0 + 1e-9);
        self.tree = Forest::build(entries);
        self.tree_id = NEXT_TREE.fetch_add(1, Ordering::Relaxed);
        self.reference.resize(x.len(), Vec3::zeros());
        self.reference
            .par_chunks_mut(SEG_CHUNK)
            .zip(x.par_chunks(SEG_CHUNK))
            .for_each(|(r, x)| r.copy_from_slice(x));
        self.skin = skin;
        self.built = true;
        self.builds += 1;
        self.drift = 0.0;
        true
    }

    /// Segments whose stored box meets the cube of half-size `r` around `p`.
    pub fn candidates(&self, p: &Vec3, r: f64, out: &mut Vec<u32>) {
        self.query(
            [p.x - r, p.y - r, p.z - r],
            [p.x + r, p.y + r, p.z + r],
            out,
        );
    }

    /// Segments whose stored box meets the box `lo`..`hi` (lo <= hi), into `out`, in no
    /// particular order (`forest.rs`).
    pub fn query(&self, lo: [f64; 3], hi: [f64; 3], out: &mut Vec<u32>) {
        self.tree.query(lo, hi, out);
    }

    /// Whether segment `j`'s stored box meets the box `lo`..`hi`: the tree's own test
    /// (rstar's `AABB::intersects`, bounds included) on the same corners.
    pub fn box_meets(&self, j: u32, lo: &[f64; 3], hi: &[f64; 3]) -> bool {
        let (blo, bhi) = &self.boxes[j as usize];
        (0..3).all(|d| blo[d] <= hi[d]) && (0..3).all(|d| bhi[d] >= lo[d])
    }

    /// Identity of the current tree (unique in the process, never reused): node lists
    /// made from another tree are stale.
    pub fn tree_id(&self) -> u64 {
        self.tree_id
    }

    /// The Verlet skin of the current tree [m].
    pub fn skin(&self) -> f64 {
        self.skin
    }

    /// Box of the body's nodes at the current pass: the union of its chunk boxes (min
    /// and max: the bits of `mesh::bounds`).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.chunks
            .iter()
            .fold(crate::mesh::bounds(&[]), |(lo, hi), k| {
                (lo.inf(&k.lo), hi.sup(&k.hi))
            })
    }

    /// Unit normal of node `n` at positions `x`: the area-weighted mean of its
    /// segments' normals, summed in the order of `smooth::nodal_normals` (so the two
    /// agree bit for bit), or zero where they cancel. The contact stage needs normals
    /// only at the nodes of its hits: computing those alone keeps the pass proportional
    /// to the contact zone, not to the body.
    pub fn nodal_normal(&self, n: u32, x: &[Vec3]) -> Vec3 {
        let (a, b) = (
            self.inc_start[n as usize] as usize,
            self.inc_start[n as usize + 1] as usize,
        );
        let mut v = Vec3::zeros();
        for &j in &self.inc[a..b] {
            v += face_vector(&self.segments[j as usize], x);
        }
        let l = v.norm();
        if l > 0.0 {
            v / l
        } else {
            Vec3::zeros()
        }
    }

    /// The segments incident to node `n`, in the summation order of its nodal normal.
    pub fn incident(&self, n: u32) -> &[u32] {
        let (a, b) = (
            self.inc_start[n as usize] as usize,
            self.inc_start[n as usize + 1] as usize,
        );
        &self.inc[a..b]
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::smooth::nodal_normals;
    use crate::material::{Material, Section};
    use crate::shapes::{plate, ElementKind};
    use crate::Stabilization;

    /// The contact stage computes normals only where a pass reads them; they must be
    /// the full field's bits (a mixed tri/quad body, moved off its plane).
    #[test]
    fn nodal_normals_of_single_nodes_equal_the_whole_field_bit_for_bit() {
        let mut m = plate(1.0, 1.0, 6, 5, ElementKind::Quad);
        for q in m.quads.drain(..7).collect::<Vec<_>>() {
            m.tris.push([q[0], q[1], q[2]]);
            m.tris.push([q[0], q[2], q[3]]);
        }
        let sec = Section::new(Material::new(1000.0, 1e9, 0.3, 0.0).expect("valid"), 0.01);
        let mut b = Body::new(0, "p", &m, sec, Stabilization::default()).expect("valid");
        let mut r = 12345u64;
        for x in &mut b.state.x {
            r = r
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            x.z += ((r >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.05;
        }
        let whole = nodal_normals(&b);
        let surf = Surface::new(&b);
        for (n, w) in whole.iter().enumerate() {
            let one = surf.nodal_normal(n as u32, &b.state.x);
            for d in 0..3 {
                assert_eq!(one[d].to_bits(), w[d].to_bits(), "node {n}");
            }
        }
    }
}
