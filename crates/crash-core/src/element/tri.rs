//! 3-node flat co-rotational Reissner–Mindlin triangle, one-point quadrature
//! (the seed's element family: Stolarski, Belytschko, Carpenter, Kennedy 1984).
//!
//! Membrane: total-Lagrangian constant-strain (see `membrane`). Bending: constant
//! curvature from the linear rotation field. Transverse shear: the assumed shear of the
//! C0 triangle (Belytschko–Stolarski–Carpenter 1984, identical to MITC3): tangential
//! shear strains tied at the edge midpoints, field a + c (-(y-yc), x-xc), evaluated at
//! the centroid; this removes the shear locking of the plain one-point triangle.
//! The kernel is generic over `Real` so that four elements run in SIMD lanes.

use super::membrane::membrane_forces;
use super::plate::{plate_forces, Consts, LocalRates, PlateKin, ShellL};
use super::real::{Real, V3};
use super::reference::{tri_gradients, Frame};
use crate::Vec3;
use serde::{Deserialize, Serialize};

/// Reference data of one triangle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TriElem {
    pub nodes: [u32; 3],
    /// Reference shape-function gradients in the initial element frame.
    pub bx0: [f64; 3],
    pub by0: [f64; 3],
    pub area0: f64,
}

impl TriElem {
    pub fn new(nodes: [u32; 3], x: &[Vec3; 3]) -> Self {
        let (fr, two_area) = Frame::triangle(x);
        let a = (x[1] - x[0]).dot(&fr.e1);
        let c = (x[2] - x[0]).dot(&fr.e1);
        let d = (x[2] - x[0]).dot(&fr.e2);
        let (bx0, by0) = tri_gradients(a, c, d);
        Self {
            nodes,
            bx0,
            by0,
            area0: 0.5 * two_area,
        }
    }
}

/// Assumed (MITC3 / C0-triangle) shear operator for local coordinates 2 = (a, 0),
/// 3 = (c, d): coefficients of w, theta_x and theta_y in the centroid shear strain.
#[allow(clippy::type_complexity)]
#[inline(always)]
pub fn tri_shear_operator<S: Real>(a: S, c: S, d: S) -> ([[S; 2]; 3], [[S; 2]; 3], [[S; 2]; 3]) {
    // edge e runs from node i to node j with vector E; u_e = l_e * (tangential shear)
    const EDGES: [(usize, usize); 3] = [(0, 1), (1, 2), (2, 0)];
    let zero = S::splat(0.0);
    let ev = [[a, zero], [c - a, d], [-c, -d]];
    let third = S::splat(1.0 / 3.0);
    let two_third = S::splat(2.0 / 3.0);
    let (ia, id) = (S::splat(1.0) / a, S::splat(1.0) / d);
    let ca = c * ia;
    let k = [
        [two_third * ia, -(two_third * ca - third) * id],
        [-(third * ia), (third + third * ca) * id],
        [-(third * ia), -(two_third - third * ca) * id],
    ];
    let half = S::splat(0.5);
    let mut cw = [[zero; 2]; 3];
    let mut cx = [[zero; 2]; 3];
    let mut cy = [[zero; 2]; 3];
    for (e, &(i, j)) in EDGES.iter().enumerate() {
        for s in 0..2 {
            cw[i][s] -= k[e][s];
            cw[j][s] += k[e][s];
            let hx = half * k[e][s] * ev[e][0];
            let hy = half * k[e][s] * ev[e][1];
            cy[i][s] += hx;
            cy[j][s] += hx;
            cx[i][s] -= hy;
            cx[j][s] -= hy;
        }
    }
    (cw, cx, cy)
}

/// Inputs of the triangle kernel (one element, or four in lanes).
#[derive(Debug, Clone, Copy)]
pub struct TriIn<S> {
    pub x: [V3<S>; 3],
    pub v: [V3<S>; 3],
    pub w: [V3<S>; 3],
    pub bx0: [S; 3],
    pub by0: [S; 3],
    pub area0: S,
}

/// What the kernel returns besides forces and state.
#[derive(Debug, Clone, Copy)]
pub struct KernelOut<S> {
    pub internal: S,
    pub damping: S,
    /// Characteristic length L_e of the current configuration.
    pub length: S,
    /// Current area / initial area (collapse check by the caller).
    pub ratio: S,
}

/// Components of `p` in the frame (e1, e2, e3).
#[inline(always)]
pub fn local<S: Real>(p: V3<S>, e1: V3<S>, e2: V3<S>, e3: V3<S>) -> [S; 3] {
    [p.dot(e1), p.dot(e2), p.dot(e3)]
}

/// Internal forces of a triangle: writes its three slots (global force, moment).
#[inline(always)]
pub fn tri_kernel<S: Real>(
    k: &Consts<S>,
    e: &TriIn<S>,
    h: S,
    st: &mut ShellL<S>,
    out: &mut [[S; 6]; 3],
) -> KernelOut<S> {
    let half = S::splat(0.5);
    let one = S::splat(1.0);
    let r2 = e.x[1].minus(e.x[0]);
    let r3 = e.x[2].minus(e.x[0]);
    let r23 = e.x[2].minus(e.x[1]);
    let n = r2.cross(r3);
    let two_area = n.norm_squared().sqrt();
    let e3 = n.scale(one / two_area);
    let l2sq = r2.norm_squared();
    let a = l2sq.sqrt();
    let e1 = r2.scale(one / a);
    let e2 = e3.cross(e1);
    let c = r3.dot(e1);
    let d = r3.dot(e2);

    let mut fm = [V3::zero(); 3];
    let zero3 = [S::splat(0.0); 3];
    let (e_mem, d_mem) = membrane_forces(
        &k.membrane,
        k.alpha,
        &e.bx0,
        &e.by0,
        e.area0,
        &zero3,
        &e.x,
        &e.v,
        h,
        &mut fm,
    );

    let (bx, by) = tri_gradients(a, c, d);
    let (cw, cx, cy) = tri_shear_operator(a, c, d);
    let kin = PlateKin {
        bx,
        by,
        area: half * two_area,
        cw,
        cx,
        cy,
    };
    let rates = LocalRates {
        v: [
            local(e.v[0], e1, e2, e3),
            local(e.v[1], e1, e2, e3),
            local(e.v[2], e1, e2, e3),
        ],
        w: [
            local(e.w[0], e1, e2, e3),
            local(e.w[1], e1, e2, e3),
            local(e.w[2], e1, e2, e3),
        ],
    };
    let mut lo = [[S::splat(0.0); 6]; 3];
    let (e_pl, d_pl) = plate_forces(k, &kin, &rates, h, st, &mut lo);
    for i in 0..3 {
        let f = fm[i]
            .plus(e1.scale(lo[i][0]))
            .plus(e2.scale(lo[i][1]))
            .plus(e3.scale(lo[i][2]));
        let m = e1
            .scale(lo[i][3])
            .plus(e2.scale(lo[i][4]))
            .plus(e3.scale(lo[i][5]));
        out[i] = [f.x, f.y, f.z, m.x, m.y, m.z];
    }
    let longest = l2sq.max(r3.norm_squared()).max(r23.norm_squared()).sqrt();
    KernelOut {
        internal: e_mem + e_pl,
        damping: d_mem + d_pl,
        length: two_area / longest,
        ratio: half * two_area / e.area0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn assumed_shear_reproduces_constant_shear() {
        let (a, c, d) = (1.3, 0.4, 0.9);
        let (cw, _, _) = tri_shear_operator(a, c, d);
        // w = gx x + gy y with zero rotations must give shear (gx, gy)
        let p = [[0.0, 0.0], [a, 0.0], [c, d]];
        let (gx, gy) = (0.7, -0.2);
        let mut g = [0.0; 2];
        for i in 0..3 {
            let w = gx * p[i][0] + gy * p[i][1];
            g[0] += cw[i][0] * w;
            g[1] += cw[i][1] * w;
        }
        assert!(
            (g[0] - gx).abs() < 1e-14 && (g[1] - gy).abs() < 1e-14,
            "{g:?}"
        );
    }

    #[test]
    fn assumed_shear_vanishes_for_kirchhoff_quadratic_deflection() {
        // w quadratic with rotations w_y = -dw/dx, w_x = dw/dy (zero shear everywhere)
        let (a, c, d) = (1.0, 0.3, 0.8);
        let (cw, cx, cy) = tri_shear_operator(a, c, d);
        let p = [[0.0, 0.0], [a, 0.0], [c, d]];
        let mut g = [0.0; 2];
        for i in 0..3 {
            let (x, y) = (p[i][0], p[i][1]);
            let w = 0.5 * x * x + 0.3 * y * y + 0.2 * x * y;
            let wy = -(x + 0.2 * y);
            let wx = 0.6 * y + 0.2 * x;
            for s in 0..2 {
                g[s] += cw[i][s] * w + cx[i][s] * wx + cy[i][s] * wy;
            }
        }
        assert!(g[0].abs() < 1e-14 && g[1].abs() < 1e-14, "{g:?}");
    }
}
