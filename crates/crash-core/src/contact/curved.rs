//! The curved contact surface of a segment for the segment pass (`quadrature.rs`): the
//! flat facet plus the quadratic bulge of the nodal normals,
//! h(w) = sum_{i<j} w_i w_j b_ij, b_ij = e_ij . (n_j - n_i) / 2, e_ij = x_j - x_i,
//! along the (sub-)triangle's unit normal (w: the segment's shape-function weights). For
//! nodes on a sphere with radial normals h is the sphere to second order (edge midpoint:
//! |e|^2 / 8R, the sagitta); on a flat segment it is zero. Along an edge only that edge's
//! two nodes count, so neighbours share the edge's curve: the surface is continuous.

use super::segment::{Corners, Segment};
use super::smooth::CREASE_COS;
use super::surface::{face_vector, Surface};
use crate::Vec3;

/// The corner normals of a segment: nodal normals, or the segment's own normal at a
/// corner on a crease (more than 30 degrees off), where a bulge would not be the surface;
/// and which corners took their nodal normal.
pub fn corner_normals(seg: &Segment, surf: &Surface, x: &[Vec3]) -> ([Vec3; 4], [bool; 4]) {
    corner_normals_with(seg, x, |_, n| surf.nodal_normal(n, x))
}

/// `corner_normals` with the nodal normals from `nodal` (a cache of
/// `Surface::nodal_normal`), asked with the corner's place in the segment and its node.
fn corner_normals_with(
    seg: &Segment,
    x: &[Vec3],
    nodal_normal: impl Fn(usize, u32) -> Vec3,
) -> ([Vec3; 4], [bool; 4]) {
    let f = face_vector(seg, x);
    let l = f.norm();
    let ns = if l > 0.0 { f / l } else { Vec3::zeros() };
    let mut out = [ns; 4];
    let mut nodal = [false; 4];
    for (k, &n) in seg.nodes().iter().enumerate() {
        let nn = nodal_normal(k, n);
        if nn.dot(&ns) >= CREASE_COS {
            out[k] = nn;
            nodal[k] = true;
        }
    }
    (out, nodal)
}

/// Adds (d n / d x)^T tau to `out` for n = F / |F|, F the sum of the face vectors of
/// `segs` (a nodal normal, or one segment's own normal).
fn unit_sum_pullback(
    segs: &[u32],
    surf: &Surface,
    x: &[Vec3],
    tau: &Vec3,
    out: &mut Vec<(u32, Vec3)>,
) {
    let mut f = Vec3::zeros();
    for &j in segs {
        f += face_vector(&surf.segments[j as usize], x);
    }
    let l = f.norm();
    if l <= 0.0 {
        return;
    }
    let n = f / l;
    let t = (tau - n * n.dot(tau)) / l;
    for &j in segs {
        let s = &surf.segments[j as usize];
        let [a, b, c, d] = s.nodes.map(|i| x[i as usize]);
        if s.count == 3 {
            // F = (b - a) x (c - a)
            let db = (c - a).cross(&t);
            let dc = t.cross(&(b - a));
            out.push((s.nodes[0], -(db + dc)));
            out.push((s.nodes[1], db));
            out.push((s.nodes[2], dc));
        } else {
            // F = (c - a) x (d - b)
            let dc = (d - b).cross(&t);
            let dd = t.cross(&(c - a));
            out.push((s.nodes[0], -dc));
            out.push((s.nodes[1], -dd));
            out.push((s.nodes[2], dc));
            out.push((s.nodes[3], dd));
        }
    }
}

/// scale * dh/dx (h at fixed weights w) in two parts: through the segment's edge vectors,
/// a force per corner node (`direct`), and through its corner normals, a load tau_k on
/// corner k's normal (`on_normal`), which `normal_pullback` turns into node forces. The
/// second is linear in tau, so the segment pass sums the loads per normal over all its
/// points and pulls each sum back once (a normal's derivative reaches the nodes of all
/// the segments around its node).
pub fn bulge_parts(
    seg: &Segment,
    x: &[Vec3],
    normals: &[Vec3; 4],
    w: &[f64; 4],
    scale: f64,
) -> ([Vec3; 4], [Vec3; 4]) {
    let n = seg.count as usize;
    let xs = seg.nodes.map(|i| x[i as usize]);
    let mut direct = [Vec3::zeros(); 4];
    let mut on_normal = [Vec3::zeros(); 4];
    for k in 0..n {
        for m in 0..n {
            if m != k {
                let ww = 0.5 * w[k] * w[m] * scale;
                direct[k] += (normals[k] - normals[m]) * ww;
                on_normal[k] += (xs[k] - xs[m]) * ww;
            }
        }
    }
    (direct, on_normal)
}

/// Which unit normal a corner carries: its node's nodal normal (the sum over the node's
/// incident segments) or, on a crease, its segment's own.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum NormalOf {
    Node(u32),
    Segment(u32),
}

impl NormalOf {
    pub fn of_corner(seg: &Segment, j: u32, nodal: &[bool; 4], k: usize) -> Self {
        if nodal[k] {
            NormalOf::Node(seg.nodes[k])
        } else {
            NormalOf::Segment(j)
        }
    }

    fn segments<'a>(&self, surf: &'a Surface, one: &'a [u32; 1]) -> &'a [u32] {
        match self {
            NormalOf::Node(n) => surf.incident(*n),
            NormalOf::Segment(_) => one,
        }
    }
}

/// Adds (d n / d x)^T tau to `out` for the unit normal `which`.
pub fn normal_pullback(
    which: NormalOf,
    surf: &Surface,
    x: &[Vec3],
    tau: &Vec3,
    out: &mut Vec<(u32, Vec3)>,
) {
    let one = match which {
        NormalOf::Segment(j) => [j],
        NormalOf::Node(_) => [0],
    };
    unit_sum_pullback(which.segments(surf, &one), surf, x, tau, out);
}

/// The rate dn/dt of the unit normal `which` for nodal velocities v.
pub fn normal_rate(which: NormalOf, surf: &Surface, x: &[Vec3], v: &[Vec3]) -> Vec3 {
    let one = match which {
        NormalOf::Segment(j) => [j],
        NormalOf::Node(_) => [0],
    };
    let segs = which.segments(surf, &one);
    let (mut f, mut df) = (Vec3::zeros(), Vec3::zeros());
    for &j in segs {
        let s = &surf.segments[j as usize];
        f += face_vector(s, x);
        let [a, b, c, d] = s.nodes.map(|i| x[i as usize]);
        let [va, vb, vc, vd] = s.nodes.map(|i| v[i as usize]);
        df += if s.count == 3 {
            (vb - va).cross(&(c - a)) + (b - a).cross(&(vc - va))
        } else {
            (vc - va).cross(&(d - b)) + (c - a).cross(&(vd - vb))
        };
    }
    let l = f.norm();
    if l <= 0.0 {
        return Vec3::zeros();
    }
    let n = f / l;
    (df - n * n.dot(&df)) / l
}

/// The pair coefficients b_ij of a segment (row-major 4 x 4, symmetric, zero diagonal).
pub fn coefficients(seg: &Segment, x: &[Vec3], normals: &[Vec3; 4]) -> [[f64; 4]; 4] {
    let mut b = [[0.0; 4]; 4];
    let n = seg.count as usize;
    for i in 0..n {
        for j in (i + 1)..n {
            let e = x[seg.nodes[j] as usize] - x[seg.nodes[i] as usize];
            let v = 0.5 * e.dot(&(normals[j] - normals[i]));
            b[i][j] = v;
            b[j][i] = v;
        }
    }
    b
}

/// A bound on |h| over a segment: the smaller of sum_{i<j} |b_ij| / 4 (weights w >= 0
/// summing to 1 give w_i w_j <= 1/4) and max |b_ij| x 3/8 (sum_{i<j} w_i w_j <= (1 -
/// 1/k) / 2 <= 3/8 for k <= 4 corners; a triangle's b has no fourth row).
pub fn bulge_bound(b: &[[f64; 4]; 4]) -> f64 {
    let (mut s, mut m) = (0.0, 0.0f64);
    for (i, row) in b.iter().enumerate() {
        for v in &row[i + 1..] {
            s += v.abs();
            m = m.max(v.abs());
        }
    }
    (0.25 * s).min(0.375 * m)
}

/// The loose bound's factor on a segment's node-box diagonal D, for a segment of
/// `corners` corners: corner normals lie within the crease angle (30 degrees) of the
/// segment's normal, so |n_j - n_i| <= 2 sin 30 = 1 and |b_ij| <= |e_ij| / 2 <= D / 2;
/// with weights w >= 0 summing to 1, sum_{i<j} w_i w_j = (1 - sum w_i^2) / 2 <=
/// (1 - 1/k) / 2 (k corners), so |h| <= (1 - 1/k) / 4 x D: D / 6 for a triangle, 3 D /
/// 16 for a quad. (Until session 31: pairs / 8 x D, from w_i w_j <= 1/4 per pair, 2.25
/// and 4 times as large.)
pub fn loose_factor(corners: usize) -> f64 {
    let k = corners as f64;
    (1.0 - 1.0 / k) / 4.0
}

/// A loose bound on the bulge of the segments `live` (node boxes `boxes`, by position in
/// `live`): `loose_factor` x the node box's diagonal, the largest.
pub fn loose_bulge_bound(surf: &Surface, live: &[u32], boxes: &[(Vec3, Vec3)]) -> f64 {
    live.iter()
        .zip(boxes)
        .map(|(&j, (lo, hi))| {
            let f = loose_factor(surf.segments[j as usize].count as usize);
            (hi - lo).norm_squared() * (f * f)
        })
        .fold(0.0, f64::max)
        .sqrt()
}

/// The node box of a segment.
pub fn node_box(seg: &Segment, x: &[Vec3]) -> (Vec3, Vec3) {
    let mut lo = x[seg.nodes[0] as usize];
    let mut hi = lo;
    for &n in &seg.nodes()[1..] {
        lo = lo.inf(&x[n as usize]);
        hi = hi.sup(&x[n as usize]);
    }
    (lo, hi)
}

/// The curved data of one segment at the current positions: its corner normals, which
/// corners took their nodal normal, and its bulge coefficients.
#[derive(Debug, Clone, Copy)]
pub struct Curved {
    pub normals: [Vec3; 4],
    pub nodal: [bool; 4],
    pub b: [[f64; 4]; 4],
}

impl Curved {
    pub fn of(seg: &Segment, surf: &Surface, x: &[Vec3]) -> Self {
        Self::with(seg, x, |_, n| surf.nodal_normal(n, x))
    }

    /// `of` with the nodal normals from `nodal` (a cache of `Surface::nodal_normal`,
    /// asked with the corner's place and its node).
    fn with(seg: &Segment, x: &[Vec3], nodal: impl Fn(usize, u32) -> Vec3) -> Self {
        let (normals, nodal) = corner_normals_with(seg, x, nodal);
        Curved {
            normals,
            nodal,
            b: coefficients(seg, x, &normals),
        }
    }
}

/// The curved data of the segments of a body near the other body of a pair, computed
/// once per pass (every point of both directions reads its slave's and its master's),
/// and the largest bulge bound over them.
#[derive(Debug)]
pub struct NearCurved {
    /// The near segments, ascending, their node boxes and their data.
    segs: Vec<u32>,
    boxes: Vec<(Vec3, Vec3)>,
    data: Vec<Curved>,
    pub bound: f64,
}

impl NearCurved {
    /// Segment j's curved data: the stored one, or computed now for a segment outside
    /// the near set (the same values either way).
    pub fn get(&self, j: u32, surf: &Surface, x: &[Vec3]) -> Curved {
        match self.index(j) {
            Some(k) => self.data[k],
            None => Curved::of(&surf.segments[j as usize], surf, x),
        }
    }

    /// Where segment j's data are stored (`at`), if it is in the near set.
    pub fn index(&self, j: u32) -> Option<usize> {
        self.segs.binary_search(&j).ok()
    }

    /// The stored data at position k (`index`).
    pub fn at(&self, k: usize) -> &Curved {
        &self.data[k]
    }

    /// The near segments, ascending.
    pub fn segs(&self) -> &[u32] {
        &self.segs
    }

    /// Their node boxes (by position in `segs`).
    pub fn boxes(&self) -> &[(Vec3, Vec3)] {
        &self.boxes
    }

    /// The segments whose node box comes within `grow` of the box `near` (per axis), and
    /// the largest bulge bound over them.
    pub fn within(self, near: &(Vec3, Vec3), grow: f64) -> NearCurved {
        let mut out = NearCurved {
            segs: Vec::new(),
            boxes: Vec::new(),
            data: Vec::new(),
            bound: 0.0,
        };
        for ((j, bx), cv) in self.segs.into_iter().zip(self.boxes).zip(self.data) {
            if meets(&bx, near, grow) {
                out.segs.push(j);
                out.boxes.push(bx);
                out.data.push(cv);
            }
        }
        out.bound = out
            .data
            .iter()
            .map(|cv| bulge_bound(&cv.b))
            .fold(0.0, f64::max);
        out
    }
}

/// Does box `b` come within `grow` of box `near` (per axis)?
fn meets(b: &(Vec3, Vec3), near: &(Vec3, Vec3), grow: f64) -> bool {
    let (lo, hi) = b;
    (0..3).all(|d| hi[d] >= near.0[d] - grow && lo[d] <= near.1[d] + grow)
}

/// The curved data of the segments `live` (ascending; node boxes `boxes`, by position
/// in `live`) of a body whose node box comes within `grow` of the box `near` (the other
/// body's, grown by what a bulge can add), and the largest bulge bound over them: how
/// far its curved surface can stand off its facets where contact can happen. `live`
/// must hold every segment of the body that comes that near. Max is order-free and the
/// data are collected in segment order: the same bits on any thread count.
pub fn near_curved(
    surf: &Surface,
    x: &[Vec3],
    live: &[u32],
    boxes: &[(Vec3, Vec3)],
    near: &(Vec3, Vec3),
    grow: f64,
) -> NearCurved {
    use rayon::prelude::*;
    let (segs, boxes): (Vec<u32>, Vec<(Vec3, Vec3)>) = live
        .iter()
        .zip(boxes)
        .filter(|(_, bx)| meets(bx, near, grow))
        .map(|(&j, &bx)| (j, bx))
        .unzip();
    // each corner node's normal once (a node is a corner of about six segments): the
    // same function, so the same bits
    let (nodes, corners) = corner_slots(surf, &segs, x.len());
    let normals: Vec<Vec3> = nodes
        .par_iter()
        .with_min_len(256)
        .map(|&n| surf.nodal_normal(n, x))
        .collect();
    let data: Vec<Curved> = segs
        .par_iter()
        .zip(&corners)
        .with_min_len(128)
        .map(|(&j, slots)| {
            Curved::with(&surf.segments[j as usize], x, |q, _| {
                normals[slots[q] as usize]
            })
        })
        .collect();
    let bound = data.iter().map(|cv| bulge_bound(&cv.b)).fold(0.0, f64::max);
    NearCurved {
        segs,
        boxes,
        data,
        bound,
    }
}

thread_local! {
    /// `corner_slots`' node-to-slot map, as large as the largest body seen on this
    /// thread, all `u32::MAX` between calls.
    static SLOTS: std::cell::RefCell<Vec<u32>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The corner nodes of `segs` (of a body of `n_nodes` nodes), each once, in order of
/// first use, and each segment's corners as places in that list. The map from node to
/// place is a scratch array per thread, reset entry by entry after use: filling an
/// array the size of the body for every pair and pass (a floor under many bodies) cost
/// more than the lookups, and sorting the nodes more still on the showcase.
fn corner_slots(surf: &Surface, segs: &[u32], n_nodes: usize) -> (Vec<u32>, Vec<[u32; 4]>) {
    SLOTS.with_borrow_mut(|slot| {
        if slot.len() < n_nodes {
            slot.resize(n_nodes, u32::MAX);
        }
        let mut nodes = Vec::new();
        let corners = segs
            .iter()
            .map(|&j| {
                let mut c = [0; 4];
                for (q, &n) in surf.segments[j as usize].nodes().iter().enumerate() {
                    let s = &mut slot[n as usize];
                    if *s == u32::MAX {
                        *s = nodes.len() as u32;
                        nodes.push(n);
                    }
                    c[q] = *s;
                }
                c
            })
            .collect();
        for &n in &nodes {
            slot[n as usize] = u32::MAX;
        }
        (nodes, corners)
    })
}

/// h(w) and its partial derivatives dh/dw_k.
pub fn bulge(b: &[[f64; 4]; 4], w: &[f64; 4]) -> (f64, [f64; 4]) {
    let mut dh = [0.0; 4];
    for (i, d) in dh.iter_mut().enumerate() {
        *d = (0..4).map(|j| w[j] * b[i][j]).sum();
    }
    let h = 0.5 * (0..4).map(|i| w[i] * dh[i]).sum::<f64>();
    (h, dh)
}

/// The (sub-)triangle (A, B, C) of a segment holding a projection, with the derivatives
/// of the segment weights w along its barycentric u (towards B) and v (towards C).
#[derive(Debug, Clone, Copy)]
pub struct SubTriangle {
    pub a: Vec3,
    pub b: Vec3,
    pub c: Vec3,
    pub dw_du: [f64; 4],
    pub dw_dv: [f64; 4],
}

pub fn sub_triangle(seg: &Segment, x: &[Vec3], sub: usize) -> SubTriangle {
    sub_triangle_at(&Corners::of(seg, x), sub)
}

/// `sub_triangle` from gathered corners (the same bits: the centroid is summed alike).
pub fn sub_triangle_at(at: &Corners, sub: usize) -> SubTriangle {
    let xs = at.xs;
    if at.count == 3 {
        return SubTriangle {
            a: xs[0],
            b: xs[1],
            c: xs[2],
            dw_du: [-1.0, 1.0, 0.0, 0.0],
            dw_dv: [-1.0, 0.0, 1.0, 0.0],
        };
    }
    let (k, k1) = (sub % 4, (sub + 1) % 4);
    let mut dw_du = [-0.25; 4];
    let mut dw_dv = [-0.25; 4];
    dw_du[k] += 1.0;
    dw_dv[k1] += 1.0;
    SubTriangle {
        a: at.centroid,
        b: xs[k],
        c: xs[k1],
        dw_du,
        dw_dv,
    }
}

impl SubTriangle {
    pub fn unit_normal(&self) -> Vec3 {
        let n = (self.b - self.a).cross(&(self.c - self.a));
        let l = n.norm();
        if l > 0.0 {
            n / l
        } else {
            Vec3::zeros()
        }
    }

    /// The inverse metric of the in-plane basis (e1, e2) and its dual vectors g1, g2
    /// (grad u, grad v of a point's projection); None on a degenerate triangle.
    fn dual(&self) -> Option<([[f64; 2]; 2], Vec3, Vec3)> {
        let (e1, e2) = (self.b - self.a, self.c - self.a);
        let (p, q, r) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
        let det = p * r - q * q;
        if det <= 0.0 {
            return None;
        }
        let gi = [[r / det, -q / det], [-q / det, p / det]];
        Some((
            gi,
            e1 * gi[0][0] + e2 * gi[0][1],
            e1 * gi[1][0] + e2 * gi[1][1],
        ))
    }

    /// Derivatives of a function f(w) of the weights of the projection of a point x on
    /// the plane, with partials `df`, by the corners A, B, C: x - P = `rho` (normal to
    /// the plane), (u, v) the projection's barycentrics. Translation invariant: they
    /// sum to minus the gradient by x.
    pub fn corner_gradients(
        &self,
        df: &[f64; 4],
        bary: &[f64; 3],
        rho: &Vec3,
    ) -> (Vec3, [Vec3; 3]) {
        let zeros = bary.iter().filter(|&&b| b <= 0.0).count();
        if zeros >= 2 {
            // at a corner: the weights do not move
            return (Vec3::zeros(), [Vec3::zeros(); 3]);
        }
        // corner weight vectors relative to corner A's (only differences are used)
        let corner_w = |k: usize| -> [f64; 4] {
            match k {
                0 => [0.0; 4],
                1 => self.dw_du,
                _ => self.dw_dv,
            }
        };
        if zeros == 1 {
            // on the edge from corner i to corner j: P = X_i + t e, w(t)
            let z = (0..3).find(|&k| bary[k] <= 0.0).unwrap_or(0);
            let (i, j) = ((z + 1) % 3, (z + 2) % 3);
            let xs = [self.a, self.b, self.c];
            let e = xs[j] - xs[i];
            let ee = e.dot(&e);
            if ee <= 0.0 {
                return (Vec3::zeros(), [Vec3::zeros(); 3]);
            }
            let t = bary[j];
            // dw/dt = W_j - W_i
            let (wi, wj) = (corner_w(i), corner_w(j));
            let ft: f64 = (0..4).map(|q| df[q] * (wj[q] - wi[q])).sum();
            let grad = e * (ft / ee);
            let mut c = [Vec3::zeros(); 3];
            c[i] = (-e * (1.0 - t) - rho) * (ft / ee);
            c[j] = (-e * t + rho) * (ft / ee);
            return (grad, c);
        }
        let Some((gi, g1, g2)) = self.dual() else {
            return (Vec3::zeros(), [Vec3::zeros(); 3]);
        };
        let (u, v) = (bary[1], bary[2]);
        let fu: f64 = (0..4).map(|k| df[k] * self.dw_du[k]).sum();
        let fv: f64 = (0..4).map(|k| df[k] * self.dw_dv[k]).sum();
        let grad = g1 * fu + g2 * fv;
        // d(u, v) = G^-1 [de1 . rho, de2 . rho] - (g1, g2) . dP_w
        let r1 = rho * (fu * gi[0][0] + fv * gi[1][0]);
        let r2 = rho * (fu * gi[0][1] + fv * gi[1][1]);
        (
            grad,
            [
                -grad * (1.0 - u - v) - r1 - r2,
                -grad * u + r1,
                -grad * v + r2,
            ],
        )
    }

    /// (d n / d corner)^T t for the unit normal n of the triangle and a vector t: the
    /// force a load t on a point carried along n at unit distance puts on A, B, C.
    pub fn normal_pullback(&self, t: &Vec3) -> [Vec3; 3] {
        let (e1, e2) = (self.b - self.a, self.c - self.a);
        let m = e1.cross(&e2);
        let l = m.norm();
        if l <= 0.0 {
            return [Vec3::zeros(); 3];
        }
        let n = m / l;
        let tt = t - n * n.dot(t);
        let db = e2.cross(&tt) / l;
        let dc = tt.cross(&e1) / l;
        [-(db + dc), db, dc]
    }

    /// Spread per-corner vectors of (A, B, C) onto the segment's nodes (a quad's centroid
    /// A to its four corners equally).
    pub fn spread(&self, seg: &Segment, sub: usize, f: &[Vec3; 3], out: &mut [Vec3; 4]) {
        if seg.count == 3 {
            for k in 0..3 {
                out[k] += f[k];
            }
        } else {
            for o in out.iter_mut() {
                *o += f[0] * 0.25;
            }
            out[sub % 4] += f[1];
            out[(sub + 1) % 4] += f[2];
        }
    }
}

/// Weights at the sub-triangle's corner A (u = v = 0) for a projection's sub-triangle.
pub fn corner_a_weights(seg: &Segment) -> [f64; 4] {
    if seg.count == 3 {
        [1.0, 0.0, 0.0, 0.0]
    } else {
        [0.25; 4]
    }
}
