//! Surface meshes of shell bodies: nodes, 3-node triangles and 4-node quads.

use crate::error::CoreError;
use crate::Vec3;
use serde::{Deserialize, Serialize};

/// Largest quad warp (max out-of-plane offset of a corner / sqrt(area)) accepted: the
/// one-point Belytschko–Lin–Tsay quad has no warping correction, so warped quads are
/// refused at input rather than silently losing moment equilibrium (docs/theory.md).
pub const WARP_LIMIT: f64 = 0.05;

/// Axis-aligned bounds of a point set.
pub fn bounds(points: &[Vec3]) -> (Vec3, Vec3) {
    let mut lo = Vec3::repeat(f64::INFINITY);
    let mut hi = Vec3::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (lo, hi)
}

#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Mesh {
    pub nodes: Vec<Vec3>,
    pub tris: Vec<[u32; 3]>,
    pub quads: Vec<[u32; 4]>,
}

impl Mesh {
    pub fn element_count(&self) -> usize {
        self.tris.len() + self.quads.len()
    }

    /// Renumber the nodes in the order the elements (triangles, then quads) first use
    /// them; nodes no element uses keep their relative order at the end. The elements
    /// and the geometry are unchanged. Returns the number of used nodes (the unused
    /// ones start there).
    pub fn number_nodes_by_first_use(&mut self) -> usize {
        let mut new_id = vec![u32::MAX; self.nodes.len()];
        let mut order = Vec::with_capacity(self.nodes.len());
        let used = self
            .tris
            .iter()
            .flatten()
            .chain(self.quads.iter().flatten());
        let take = |n: u32, new_id: &mut [u32], order: &mut Vec<u32>| {
            if new_id[n as usize] == u32::MAX {
                new_id[n as usize] = order.len() as u32;
                order.push(n);
            }
        };
        used.for_each(|&n| take(n, &mut new_id, &mut order));
        let used_count = order.len();
        (0..self.nodes.len() as u32).for_each(|n| take(n, &mut new_id, &mut order));
        self.nodes = order.iter().map(|&n| self.nodes[n as usize]).collect();
        for t in &mut self.tris {
            *t = t.map(|n| new_id[n as usize]);
        }
        for q in &mut self.quads {
            *q = q.map(|n| new_id[n as usize]);
        }
        used_count
    }

    /// Apply a rigid rotation (3x3, orthonormal) and then a translation.
    pub fn transform(&mut self, rotation: &nalgebra::Matrix3<f64>, translation: Vec3) {
        for p in &mut self.nodes {
            *p = rotation * *p + translation;
        }
    }

    /// Check indices, finite coordinates, degenerate, non-convex and warped elements.
    pub fn validate(&self, body: &str) -> Result<(), CoreError> {
        let nn = self.nodes.len();
        if self.element_count() == 0 {
            return Err(CoreError::Empty { body: body.into() });
        }
        for (i, p) in self.nodes.iter().enumerate() {
            if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                return Err(CoreError::NonFiniteNode {
                    body: body.into(),
                    node: i,
                });
            }
        }
        let scale = self.length_scale();
        let check = |e: usize, nodes: &[u32]| -> Result<(), CoreError> {
            for &n in nodes {
                if n as usize >= nn {
                    return Err(CoreError::NodeIndex {
                        body: body.into(),
                        element: e,
                        node: n,
                        nodes: nn,
                    });
                }
            }
            Ok(())
        };
        for (e, t) in self.tris.iter().enumerate() {
            check(e, t)?;
            let p = t.map(|n| self.nodes[n as usize]);
            let area = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
            if area.is_nan() || area <= 1e-12 * scale * scale {
                return Err(CoreError::Degenerate {
                    body: body.into(),
                    element: e,
                    area,
                });
            }
        }
        let nt = self.tris.len();
        for (q, quad) in self.quads.iter().enumerate() {
            let e = nt + q;
            check(e, quad)?;
            let p = quad.map(|n| self.nodes[n as usize]);
            let normal = (p[2] - p[0]).cross(&(p[3] - p[1]));
            let area = 0.5 * normal.norm();
            if area.is_nan() || area <= 1e-12 * scale * scale {
                return Err(CoreError::Degenerate {
                    body: body.into(),
                    element: e,
                    area,
                });
            }
            let n = normal / normal.norm();
            for c in 0..4 {
                let a = p[(c + 1) % 4] - p[c];
                let b = p[(c + 3) % 4] - p[c];
                if a.cross(&b).dot(&n) <= 0.0 {
                    return Err(CoreError::NonConvex {
                        body: body.into(),
                        element: e,
                        corner: c,
                    });
                }
            }
            let centre = (p[0] + p[1] + p[2] + p[3]) * 0.25;
            let warp = p
                .iter()
                .map(|x| (x - centre).dot(&n).abs())
                .fold(0.0, f64::max)
                / area.sqrt();
            if warp > WARP_LIMIT {
                return Err(CoreError::Warped {
                    body: body.into(),
                    element: e,
                    warp,
                    limit: WARP_LIMIT,
                });
            }
        }
        Ok(())
    }

    /// Diagonal of the bounding box (a length scale for tolerances).
    pub fn length_scale(&self) -> f64 {
        let (lo, hi) = self.bounds();
        (hi - lo).norm().max(f64::MIN_POSITIVE)
    }

    pub fn bounds(&self) -> (Vec3, Vec3) {
        bounds(&self.nodes)
    }

    /// Total area of the surface.
    pub fn area(&self) -> f64 {
        let mut a = 0.0;
        for t in &self.tris {
            let p = t.map(|n| self.nodes[n as usize]);
            a += 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
        }
        for q in &self.quads {
            let p = q.map(|n| self.nodes[n as usize]);
            a += 0.5 * (p[2] - p[0]).cross(&(p[3] - p[1])).norm();
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Mesh {
        Mesh {
            nodes: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            tris: vec![],
            quads: vec![[0, 1, 2, 3]],
        }
    }

    #[test]
    fn flat_square_is_valid_and_has_unit_area() {
        let m = square();
        m.validate("b").expect("valid");
        assert!((m.area() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn warped_quad_is_refused() {
        let mut m = square();
        m.nodes[2].z = 0.3;
        assert!(matches!(m.validate("b"), Err(CoreError::Warped { .. })));
    }

    #[test]
    fn degenerate_triangle_is_refused() {
        let m = Mesh {
            nodes: vec![Vec3::zeros(), Vec3::x(), Vec3::x() * 2.0],
            tris: vec![[0, 1, 2]],
            quads: vec![],
        };
        assert!(matches!(m.validate("b"), Err(CoreError::Degenerate { .. })));
    }

    #[test]
    fn numbering_by_first_use_keeps_every_element_and_its_geometry() {
        let mut m = square();
        m.nodes.push(Vec3::new(5.0, 5.0, 5.0)); // used by no element: kept, at the end
        m.quads[0] = [2, 3, 0, 1];
        let (area, corners) = (m.area(), m.quads[0].map(|n| m.nodes[n as usize]));
        assert_eq!(m.number_nodes_by_first_use(), 4);
        assert_eq!(m.quads[0], [0, 1, 2, 3]);
        assert_eq!(m.quads[0].map(|n| m.nodes[n as usize]), corners);
        assert_eq!(m.nodes[4], Vec3::new(5.0, 5.0, 5.0));
        assert_eq!(m.area(), area);
    }

    #[test]
    fn bad_index_is_refused() {
        let mut m = square();
        m.quads[0][3] = 9;
        assert!(matches!(
            m.validate("b"),
            Err(CoreError::NodeIndex { node: 9, .. })
        ));
    }
}
