//! Reference (initial) geometry of elements: co-rotational frames and gradients.

use super::real::Real;
use crate::Vec3;

/// An orthonormal element frame: e1, e2 in the element plane, e3 its normal.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    pub e1: Vec3,
    pub e2: Vec3,
    pub e3: Vec3,
}

impl Frame {
    /// Triangle frame: e1 along edge 1-2, e3 the normal of (x2-x1) x (x3-x1).
    /// Returns the frame and twice the area.
    #[inline(always)]
    pub fn triangle(x: &[Vec3; 3]) -> (Self, f64) {
        let a = x[1] - x[0];
        let b = x[2] - x[0];
        let n = a.cross(&b);
        let two_area = n.norm();
        let e3 = n / two_area;
        let e1 = a / a.norm();
        let e2 = e3.cross(&e1);
        (Self { e1, e2, e3 }, two_area)
    }

    /// Belytschko–Lin–Tsay quad frame: e3 normal to the diagonals, e1 along edge 1-2
    /// projected on the plane. Returns the frame and the centre.
    #[inline(always)]
    pub fn quad(x: &[Vec3; 4]) -> (Self, Vec3) {
        let n = (x[2] - x[0]).cross(&(x[3] - x[1]));
        let e3 = n / n.norm();
        let r = x[1] - x[0];
        let r = r - e3 * r.dot(&e3);
        let e1 = r / r.norm();
        let e2 = e3.cross(&e1);
        let c = (x[0] + x[1] + x[2] + x[3]) * 0.25;
        (Self { e1, e2, e3 }, c)
    }

    /// Components of a global vector in this frame.
    #[inline(always)]
    pub fn local(&self, v: &Vec3) -> [f64; 3] {
        [v.dot(&self.e1), v.dot(&self.e2), v.dot(&self.e3)]
    }

    /// Global vector from local components.
    #[inline(always)]
    pub fn global(&self, l: [f64; 3]) -> Vec3 {
        self.e1 * l[0] + self.e2 * l[1] + self.e3 * l[2]
    }
}

/// Gradients of the linear triangle's shape functions from local coordinates of nodes
/// 2 = (a, 0) and 3 = (c, d), node 1 at the origin: returns (bx, by).
#[inline(always)]
pub fn tri_gradients<S: Real>(a: S, c: S, d: S) -> ([S; 3], [S; 3]) {
    let inv = S::splat(1.0) / (a * d); // 1 / (2A)
    (
        [-(d * inv), d * inv, S::splat(0.0)],
        [(c - a) * inv, -(c * inv), a * inv],
    )
}

/// Centroid gradients of the bilinear quad from local nodal coordinates
/// (Belytschko–Lin–Tsay B matrix), with the area: returns (bx, by, area).
#[inline(always)]
pub fn quad_gradients<S: Real>(xl: [S; 4], yl: [S; 4]) -> ([S; 4], [S; 4], S) {
    let x31 = xl[2] - xl[0];
    let x42 = xl[3] - xl[1];
    let y31 = yl[2] - yl[0];
    let y42 = yl[3] - yl[1];
    let half = S::splat(0.5);
    let area = half * (x31 * y42 - x42 * y31);
    let inv = half / area;
    (
        [-(y42 * inv), y31 * inv, y42 * inv, -(y31 * inv)],
        [x42 * inv, -(x31 * inv), -(x42 * inv), x31 * inv],
        area,
    )
}
