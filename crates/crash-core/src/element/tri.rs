//! 3-node flat co-rotational Reissner–Mindlin triangle, one-point quadrature
//! (the seed's element family: Stolarski, Belytschko, Carpenter, Kennedy 1984).
//!
//! Membrane: total-Lagrangian constant-strain (see `membrane`). Bending: constant
//! curvature from the linear rotation field. Transverse shear: the assumed shear of the
//! C0 triangle (Belytschko–Stolarski–Carpenter 1984, identical to MITC3): tangential
//! shear strains tied at the edge midpoints, field a + c (-(y-yc), x-xc), evaluated at
//! the centroid; this removes the shear locking of the plain one-point triangle.

use super::membrane::membrane_forces;
use super::plate::{plate_forces, LocalRates, PlateKin};
use super::reference::{tri_gradients, Frame};
use super::{ElemEnergy, ElemFailure, ShellState, Slot, Stabilization, COLLAPSE_RATIO};
use crate::material::Section;
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
pub fn tri_shear_operator(a: f64, c: f64, d: f64) -> ([[f64; 2]; 3], [[f64; 2]; 3], [[f64; 2]; 3]) {
    // edge e runs from node i to node j with vector E; u_e = l_e * (tangential shear)
    const EDGES: [(usize, usize); 3] = [(0, 1), (1, 2), (2, 0)];
    let ev = [[a, 0.0], [c - a, d], [-c, -d]];
    let third = 1.0 / 3.0;
    let ca = c / a;
    let k = [
        [2.0 * third / a, -(-third + 2.0 * third * ca) / d],
        [-third / a, -(-third - third * ca) / d],
        [-third / a, -(2.0 * third - third * ca) / d],
    ];
    let mut cw = [[0.0; 2]; 3];
    let mut cx = [[0.0; 2]; 3];
    let mut cy = [[0.0; 2]; 3];
    for (e, &(i, j)) in EDGES.iter().enumerate() {
        for s in 0..2 {
            cw[i][s] -= k[e][s];
            cw[j][s] += k[e][s];
            let hx = 0.5 * k[e][s] * ev[e][0];
            let hy = 0.5 * k[e][s] * ev[e][1];
            cy[i][s] += hx;
            cy[j][s] += hx;
            cx[i][s] -= hy;
            cx[j][s] -= hy;
        }
    }
    (cw, cx, cy)
}

/// Internal forces of one triangle. Writes its three slots; returns the characteristic
/// length L_e = 2 A / longest edge of the current configuration.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn tri_forces(
    sec: &Section,
    stab: &Stabilization,
    el: &TriElem,
    x: &[Vec3; 3],
    v: &[Vec3; 3],
    w: &[Vec3; 3],
    h: f64,
    st: &mut ShellState,
    out: &mut [Slot; 3],
    en: &mut ElemEnergy,
) -> Result<f64, ElemFailure> {
    let (fr, two_area) = Frame::triangle(x);
    let ratio = 0.5 * two_area / el.area0;
    if !(ratio >= COLLAPSE_RATIO) {
        return Err(ElemFailure::Collapsed { ratio });
    }
    let mut fm = [Vec3::zeros(); 3];
    membrane_forces(sec, &el.bx0, &el.by0, el.area0, &[0.0; 3], x, v, h, &mut fm, en);

    let r2 = x[1] - x[0];
    let r3 = x[2] - x[0];
    let a = r2.dot(&fr.e1);
    let c = r3.dot(&fr.e1);
    let d = r3.dot(&fr.e2);
    let (bx, by) = tri_gradients(a, c, d);
    let (cw, cx, cy) = tri_shear_operator(a, c, d);
    let kin = PlateKin {
        bx,
        by,
        area: 0.5 * two_area,
        cw,
        cx,
        cy,
    };
    let rates = LocalRates {
        v: [fr.local(&v[0]), fr.local(&v[1]), fr.local(&v[2])],
        w: [fr.local(&w[0]), fr.local(&w[1]), fr.local(&w[2])],
    };
    let mut loc = [[0.0; 6]; 3];
    let drill_k = stab.drilling * sec.material.shear_modulus() * sec.thickness;
    plate_forces(sec, drill_k, &kin, &rates, h, st, &mut loc, en);
    for i in 0..3 {
        let f = fm[i] + fr.global([loc[i][0], loc[i][1], loc[i][2]]);
        let m = fr.global([loc[i][3], loc[i][4], loc[i][5]]);
        out[i] = [f.x, f.y, f.z, m.x, m.y, m.z];
    }
    let longest = r2
        .norm_squared()
        .max(r3.norm_squared())
        .max((x[2] - x[1]).norm_squared())
        .sqrt();
    Ok(two_area / longest)
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
        assert!((g[0] - gx).abs() < 1e-14 && (g[1] - gy).abs() < 1e-14, "{g:?}");
    }

    #[test]
    fn assumed_shear_vanishes_for_kirchhoff_linear_rotation() {
        // w = x^2/2 with theta_y = -x (so that w_y + dw/dx = 0 along every edge midpoint)
        let (a, c, d) = (1.0, 0.3, 0.8);
        let (cw, cx, cy) = tri_shear_operator(a, c, d);
        let p = [[0.0, 0.0], [a, 0.0], [c, d]];
        let mut g = [0.0; 2];
        for i in 0..3 {
            let (x, y) = (p[i][0], p[i][1]);
            let w = 0.5 * x * x + 0.3 * y * y + 0.2 * x * y;
            let wy = -(x + 0.2 * y); // w_y = -dw/dx
            let wx = 0.6 * y + 0.2 * x; // w_x = dw/dy
            for s in 0..2 {
                g[s] += cw[i][s] * w + cx[i][s] * wx + cy[i][s] * wy;
            }
        }
        assert!(g[0].abs() < 1e-14 && g[1].abs() < 1e-14, "{g:?}");
    }
}
