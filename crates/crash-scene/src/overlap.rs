//! Bodies interpenetrating at t = 0 (a stop-gap until the core's
//! `crash_core::contact::initial_penetrations` exists; the lead switches to it).
//!
//! Thickness-inflated bounding boxes overlapping is not an error by itself (a sphere
//! resting on a plate has overlapping boxes): for such pairs every node of one body is
//! measured against the other's surface, and a node nearer than the sum of the half
//! thicknesses is a penetration. A node deep inside a closed body, farther than that
//! from every face, is not detected.

use crash_core::contact::ContactConfig;
use crash_core::mesh::bounds;
use crash_core::{Body, Vec3};
use std::collections::HashMap;

/// A node of body `a` lies `distance` from element `element` of body `b`, less than the
/// `required` half-thickness sum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Penetration {
    pub a: u32,
    pub node: usize,
    pub b: u32,
    pub element: usize,
    pub distance: f64,
    pub required: f64,
}

/// Distance from `p` to the triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
pub fn point_triangle_distance(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.norm();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.norm();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).norm();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.norm();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).norm();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).norm();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (p - (a + ab * v + ac * w)).norm()
}

/// Triangles of a body's surface (quads split in two), each with its element index.
fn triangles(b: &Body) -> Vec<([Vec3; 3], usize)> {
    let x = &b.x;
    let mut out = Vec::with_capacity(b.tris.len() + 2 * b.quads.len());
    for (e, t) in b.tris.iter().enumerate() {
        out.push((t.nodes.map(|n| x[n as usize]), e));
    }
    let nt = b.tris.len();
    for (k, q) in b.quads.iter().enumerate() {
        let p = q.nodes.map(|n| x[n as usize]);
        out.push(([p[0], p[1], p[2]], nt + k));
        out.push(([p[0], p[2], p[3]], nt + k));
    }
    out
}

/// Deepest penetration of `a`'s nodes into `b`'s surface, if any.
fn nodes_into(a: &Body, b: &Body) -> Option<Penetration> {
    let required = 0.5 * (a.section.thickness + b.section.thickness);
    let tris = triangles(b);
    let (blo, bhi) = bounds(&b.x);
    let (blo, bhi) = (blo.add_scalar(-required), bhi.add_scalar(required));
    // uniform grid over b's triangles (inflated by `required`), cells about one element
    let mean: f64 = tris
        .iter()
        .map(|(p, _)| (p[1] - p[0]).norm().max((p[2] - p[0]).norm()))
        .sum::<f64>()
        / tris.len().max(1) as f64;
    let cell = mean.max(required).max(f64::MIN_POSITIVE);
    let key = |p: Vec3| ((p - blo) / cell).map(|c| c.floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    for (k, (p, _)) in tris.iter().enumerate() {
        let (lo, hi) = bounds(p);
        let (kl, kh) = (key(lo.add_scalar(-required)), key(hi.add_scalar(required)));
        for i in kl.x..=kh.x {
            for j in kl.y..=kh.y {
                for l in kl.z..=kh.z {
                    grid.entry([i, j, l]).or_default().push(k as u32);
                }
            }
        }
    }
    let mut worst: Option<Penetration> = None;
    for (n, &p) in a.x.iter().enumerate() {
        if (0..3).any(|d| p[d] < blo[d] || p[d] > bhi[d]) {
            continue;
        }
        let k = key(p);
        let Some(cands) = grid.get(&[k.x, k.y, k.z]) else {
            continue;
        };
        for &t in cands {
            let (q, e) = &tris[t as usize];
            let d = point_triangle_distance(p, q[0], q[1], q[2]);
            // a hair of tolerance: bodies placed exactly touching are accepted
            if d < required * (1.0 - 1e-9) && worst.is_none_or(|w| d < w.distance) {
                worst = Some(Penetration {
                    a: a.id,
                    node: n,
                    b: b.id,
                    element: *e,
                    distance: d,
                    required,
                });
            }
        }
    }
    worst
}

/// The first pair of contact bodies (in id order) that interpenetrate at t = 0, with its
/// deepest node. None when contact is off or no pair touches.
pub fn check_initial_overlap(bodies: &[Body], cfg: &ContactConfig) -> Option<Penetration> {
    if !cfg.enabled {
        return None;
    }
    let boxes: Vec<(Vec3, Vec3)> = bodies
        .iter()
        .map(|b| {
            let (lo, hi) = bounds(&b.x);
            let r = 0.5 * b.section.thickness;
            (lo.add_scalar(-r), hi.add_scalar(r))
        })
        .collect();
    for i in 0..bodies.len() {
        for j in i + 1..bodies.len() {
            let (a, b) = (&bodies[i], &bodies[j]);
            if !(a.contact && b.contact) {
                continue;
            }
            let ((alo, ahi), (blo, bhi)) = (boxes[i], boxes[j]);
            if (0..3).any(|d| ahi[d] < blo[d] || bhi[d] < alo[d]) {
                continue;
            }
            let found = [nodes_into(a, b), nodes_into(b, a)]
                .into_iter()
                .flatten()
                .min_by(|p, q| p.distance.total_cmp(&q.distance));
            if found.is_some() {
                return found;
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_triangle_distance_in_each_region() {
        let (a, b, c) = (Vec3::zeros(), Vec3::x(), Vec3::y());
        // above the face
        assert!((point_triangle_distance(Vec3::new(0.2, 0.2, 0.5), a, b, c) - 0.5).abs() < 1e-15);
        // beyond vertex a
        let d = point_triangle_distance(Vec3::new(-1.0, -1.0, 0.0), a, b, c);
        assert!((d - 2f64.sqrt()).abs() < 1e-15);
        // beyond edge bc: distance to the hypotenuse x + y = 1
        let d = point_triangle_distance(Vec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((d - 0.5f64.sqrt()).abs() < 1e-15);
        // beside edge ab
        let d = point_triangle_distance(Vec3::new(0.5, -0.3, 0.4), a, b, c);
        assert!((d - 0.5).abs() < 1e-15);
    }

    fn plate_at(id: u32, z: f64, t: f64) -> Body {
        use crash_core::shapes::{plate, ElementKind};
        use crash_core::{Material, Section, Stabilization};
        let mut m = plate(1.0, 1.0, 4, 4, ElementKind::Quad);
        m.transform(&nalgebra::Matrix3::identity(), Vec3::new(0.0, 0.0, z));
        let mat = Material::new(7800.0, 200e9, 0.3, 0.0).expect("valid");
        let mut b =
            Body::new(id, "p", &m, Section::new(mat, t), Stabilization::default()).expect("valid");
        b.contact = true;
        b
    }

    #[test]
    fn parallel_plates_closer_than_their_half_thicknesses_interpenetrate() {
        let cfg = ContactConfig::default();
        // half thicknesses 0.01 + 0.02 = 0.03 m
        let close = [plate_at(0, 0.0, 0.02), plate_at(1, 0.025, 0.04)];
        let p = check_initial_overlap(&close, &cfg).expect("penetration");
        assert!((p.distance - 0.025).abs() < 1e-12 && (p.required - 0.03).abs() < 1e-15);
        assert_eq!((p.a, p.b), (0, 1));
        let apart = [plate_at(0, 0.0, 0.02), plate_at(1, 0.031, 0.04)];
        assert_eq!(check_initial_overlap(&apart, &cfg), None);
        let off = ContactConfig {
            enabled: false,
            ..cfg
        };
        assert_eq!(check_initial_overlap(&close, &off), None);
        let mut no_contact = close.clone();
        no_contact[1].contact = false;
        assert_eq!(check_initial_overlap(&no_contact, &cfg), None);
    }
}
