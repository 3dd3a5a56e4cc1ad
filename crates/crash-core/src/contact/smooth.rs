//! The contact normal smoothed over facets (docs/theory-contact.md, "Normal: smoothed
//! over facets").
//!
//! Nodal normals are the area-weighted means of the adjacent face normals. On a
//! (sub-)triangle (A, B, C) of the closest segment the normal field is interpolated
//! linearly, `N(u, v) = n_A + u (n_B - n_A) + v (n_C - n_A)`, and the node s is
//! projected *along* it: the point `P(u, v) = A + u (B - A) + v (C - A)` with
//! `x_s = P + lambda N(u, v)` (three Newton iterations from the closest point). The
//! penalty force acts along `x_s - P`, on the node and, with the weights of P, on the
//! segment's nodes: equal and opposite (the weights sum to 1) and on one line (no
//! moment), so linear and angular momentum are conserved exactly as before; its
//! magnitude still comes from the exact closest-point gap.

use super::segment::{Projection, Segment};
use crate::body::Body;
use crate::Vec3;

/// A corner whose nodal normal is farther than this from the segment's own normal
/// (cosine; 30 degrees) sits on a crease: a segment with such a corner is not smoothed
/// (closest point, as on any sharp edge: the result must not depend on which of two
/// equally close segments at the crease a node took).
pub const CREASE_COS: f64 = 0.866;

/// Newton iterations of the projection along the interpolated normal (fixed: the result
/// is the same function of the geometry everywhere).
pub const NEWTON_ITERATIONS: usize = 3;

/// A projection along the normal may land this far outside its (sub-)triangle (in
/// barycentric weight); beyond, the closest point is used.
pub const OUTSIDE_TOLERANCE: f64 = 0.25;

/// Area-weighted nodal normals of a body at its current positions (unit length, or zero
/// for a node whose faces cancel): each triangle adds (x2 - x1) x (x3 - x1), each quad
/// (x3 - x1) x (x4 - x2).
pub fn nodal_normals(body: &Body) -> Vec<Vec3> {
    let x = &body.state.x;
    let mut n = vec![Vec3::zeros(); x.len()];
    // corner by corner (all first corners in element order, then all second ...): the
    // summation order of every node is a function of the mesh alone
    let tri: Vec<Vec3> = body
        .def
        .tris
        .iter()
        .map(|e| {
            let [a, b, c] = e.nodes.map(|i| x[i as usize]);
            (b - a).cross(&(c - a))
        })
        .collect();
    for k in 0..3 {
        for (e, f) in body.def.tris.iter().zip(&tri) {
            n[e.nodes[k] as usize] += f;
        }
    }
    let quad: Vec<Vec3> = body
        .def
        .quads
        .iter()
        .map(|e| {
            let [a, b, c, d] = e.nodes.map(|i| x[i as usize]);
            (c - a).cross(&(d - b))
        })
        .collect();
    for k in 0..4 {
        for (e, f) in body.def.quads.iter().zip(&quad) {
            n[e.nodes[k] as usize] += f;
        }
    }
    for v in &mut n {
        let l = v.norm();
        *v = if l > 0.0 { *v / l } else { Vec3::zeros() };
    }
    n
}

/// The segment's own unit normal (triangle: (x2 - x1) x (x3 - x1); quad: the diagonals).
fn segment_normal(seg: &Segment, x: &[Vec3]) -> Vec3 {
    let xs = seg.nodes.map(|i| x[i as usize]);
    let f = if seg.count == 3 {
        (xs[1] - xs[0]).cross(&(xs[2] - xs[0]))
    } else {
        (xs[2] - xs[0]).cross(&(xs[3] - xs[1]))
    };
    let l = f.norm();
    if l > 0.0 {
        f / l
    } else {
        Vec3::zeros()
    }
}

/// Is the segment smooth: every corner's nodal normal within the crease angle of the
/// segment's own normal `ns`?
fn smooth_segment(seg: &Segment, ns: &Vec3, normals: &[Vec3]) -> bool {
    seg.nodes()
        .iter()
        .all(|&i| normals[i as usize].dot(ns) >= CREASE_COS)
}

/// The direction and weights of a hit: along the smoothed normal, then the common normal
/// with the node's own normal `n_own`; None (closest point) on a crease segment, on the
/// mid-surface, or where the projection fails. `n_cp` is the closest-point direction.
#[allow(clippy::too_many_arguments)]
pub fn smoothed(
    p: &Vec3,
    seg: &Segment,
    pr: &Projection,
    x: &[Vec3],
    normals: &[Vec3],
    n_own: &Vec3,
    n_cp: &Vec3,
    c: f64,
) -> Option<Smoothed> {
    if pr.dist <= 1e-9 * c || !smooth_segment(seg, &segment_normal(seg, x), normals) {
        return None;
    }
    let first = along_normal(p, seg, pr, x, normals, c);
    let n_seg = first.as_ref().map_or(*n_cp, |s| s.direction);
    common_normal(p, seg, pr, x, &n_seg, n_own).or(first)
}

/// Where the penalty acts: the segment weights of the point P and the unit direction
/// from P to the node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Smoothed {
    pub weights: [f64; 4],
    pub direction: Vec3,
}

/// Solve J d = r for a 3x3 J given by columns (Cramer's rule).
fn solve3(j0: &Vec3, j1: &Vec3, j2: &Vec3, r: &Vec3) -> Option<Vec3> {
    let det = j0.dot(&j1.cross(j2));
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    Some(Vec3::new(
        r.dot(&j1.cross(j2)) / det,
        j0.dot(&r.cross(j2)) / det,
        j0.dot(&j1.cross(r)) / det,
    ))
}

/// The projection of node position `p` along the interpolated normal of segment `seg`
/// (positions `x`, nodal normals `normals` of the segment's body), starting from the
/// closest-point projection `pr`. None: the node lies on the mid-surface, the normals
/// are degenerate or the projection lands outside: use the closest point.
pub fn along_normal(
    p: &Vec3,
    seg: &Segment,
    pr: &Projection,
    x: &[Vec3],
    normals: &[Vec3],
    c: f64,
) -> Option<Smoothed> {
    if pr.dist <= 1e-9 * c {
        return None;
    }
    let ns = segment_normal(seg, x);
    if !smooth_segment(seg, &ns, normals) {
        return None;
    }
    let xs = seg.nodes.map(|i| x[i as usize]);
    let nn = seg.nodes.map(|i| normals[i as usize]);
    // the (sub-)triangle (A, B, C) that holds the closest point and its corner normals
    let (a, b, cc, na, nb, nc, k) = if seg.count == 3 {
        (xs[0], xs[1], xs[2], nn[0], nn[1], nn[2], 0)
    } else {
        let k = pr.sub as usize;
        let k1 = (k + 1) % 4;
        let cen = (xs[0] + xs[1] + xs[2] + xs[3]) * 0.25;
        let ncen = (nn[0] + nn[1] + nn[2] + nn[3]) * 0.25;
        (cen, xs[k], xs[k1], ncen, nn[k], nn[k1], k)
    };
    let (eu, ev) = (b - a, cc - a);
    let (mu, mv) = (nb - na, nc - na);
    let (mut u, mut v) = (pr.bary[1], pr.bary[2]);
    let n0 = na + mu * u + mv * v;
    let n2 = n0.norm_squared();
    if n2 == 0.0 || !n2.is_finite() {
        return None;
    }
    let mut lambda = (p - pr.point).dot(&n0) / n2;
    for _ in 0..NEWTON_ITERATIONS {
        let n = na + mu * u + mv * v;
        let f = a + eu * u + ev * v + n * lambda - p;
        let d = solve3(&(eu + mu * lambda), &(ev + mv * lambda), &n, &f)?;
        u -= d.x;
        v -= d.y;
        lambda -= d.z;
    }
    let weights = sub_triangle_weights(seg.count == 3, k, u, v)?;
    let point = xs[0] * weights[0] + xs[1] * weights[1] + xs[2] * weights[2] + xs[3] * weights[3];
    let d = p - point;
    let l = d.norm();
    if !(l > 1e-9 * c && l.is_finite()) || d.dot(&(p - pr.point)) <= 0.0 {
        return None;
    }
    Some(Smoothed {
        weights,
        direction: d / l,
    })
}

/// The common normal of a hit: the mean of the segment side's direction `n_seg` (from
/// the segment to the node) and the node's own nodal normal `n_own` turned the same way
/// (away from the segment), then the point of the segment's (sub-)triangle plane that
/// lies on the line through the node along it (so the force and its reaction act on one
/// line). None: the node's normal is missing or beyond the crease angle, or the line
/// misses the (sub-)triangle by more than the tolerance.
pub fn common_normal(
    p: &Vec3,
    seg: &Segment,
    pr: &Projection,
    x: &[Vec3],
    n_seg: &Vec3,
    n_own: &Vec3,
) -> Option<Smoothed> {
    let s = n_own.dot(n_seg);
    if s.abs() < CREASE_COS {
        return None;
    }
    let m = n_seg + if s > 0.0 { *n_own } else { -n_own };
    let l = m.norm();
    if l == 0.0 {
        return None;
    }
    let m = m / l;
    let xs = seg.nodes.map(|i| x[i as usize]);
    let (a, b, cc, k) = if seg.count == 3 {
        (xs[0], xs[1], xs[2], 0)
    } else {
        let k = pr.sub as usize;
        (
            (xs[0] + xs[1] + xs[2] + xs[3]) * 0.25,
            xs[k],
            xs[(k + 1) % 4],
            k,
        )
    };
    let (eu, ev) = (b - a, cc - a);
    // p - t m = a + u eu + v ev
    let r = p - a;
    let sol = solve3(&eu, &ev, &m, &r)?;
    let (u, v) = (sol.x, sol.y);
    let weights = sub_triangle_weights(seg.count == 3, k, u, v)?;
    let point = xs[0] * weights[0] + xs[1] * weights[1] + xs[2] * weights[2] + xs[3] * weights[3];
    let d = p - point;
    let l = d.norm();
    if !(l > 0.0 && l.is_finite()) || d.dot(n_seg) <= 0.0 {
        return None;
    }
    Some(Smoothed {
        weights,
        direction: d / l,
    })
}

/// Nodal weights of the point (u, v) of sub-triangle `k` of a segment (a triangle's
/// own nodes, or a quad's centre and nodes k, k+1), None when the point lies outside
/// it by more than the tolerance.
fn sub_triangle_weights(triangle: bool, k: usize, u: f64, v: f64) -> Option<[f64; 4]> {
    let t = OUTSIDE_TOLERANCE;
    if !(u >= -t && v >= -t && u + v <= 1.0 + t && u.is_finite() && v.is_finite()) {
        return None;
    }
    let w0 = 1.0 - u - v;
    let mut weights = [0.0; 4];
    if triangle {
        weights[0] = w0;
        weights[1] = u;
        weights[2] = v;
    } else {
        weights = [0.25 * w0; 4];
        weights[k] += u;
        weights[(k + 1) % 4] += v;
    }
    Some(weights)
}
