//! 3-node flat co-rotational Reissner–Mindlin triangle, one-point quadrature
//! (the seed's element family: Stolarski, Belytschko, Carpenter, Kennedy 1984).
//!
//! Membrane: total-Lagrangian constant-strain (see `membrane`). Bending: constant
//! curvature from the linear rotation field. Transverse shear: the assumed shear of the
//! C0 triangle (Belytschko–Stolarski–Carpenter 1984, identical to MITC3): tangential
//! shear strains tied at the edge midpoints, field a + c (-(y-yc), x-xc), evaluated at
//! the centroid; this removes the shear locking of the plain one-point triangle.
//! The kernel is generic over `Real` so that four elements run in SIMD lanes.

use super::membrane::membrane_stress;
use super::plate::{plate_update, Consts, ShellL};
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
    // edge e runs from node i to node j with vector E_e (edges 1->2, 2->3, 3->1);
    // u_e = l_e * (tangential shear); node I collects +k_e from the edge ending at I and
    // -k_e from the edge starting there, and half of each adjacent edge's rotation term.
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
    // half k_e E_e for E_1 = (a, 0), E_2 = (c - a, d), E_3 = (-c, -d)
    let (cma, mc) = (c - a, -c);
    let hx = [
        [half * k[0][0] * a, half * k[0][1] * a],
        [half * k[1][0] * cma, half * k[1][1] * cma],
        [half * k[2][0] * mc, half * k[2][1] * mc],
    ];
    let md = -d;
    // E_1 has no y component
    let hy1 = [half * k[1][0] * d, half * k[1][1] * d];
    let hy2 = [half * k[2][0] * md, half * k[2][1] * md];
    let cw = [
        [k[2][0] - k[0][0], k[2][1] - k[0][1]],
        [k[0][0] - k[1][0], k[0][1] - k[1][1]],
        [k[1][0] - k[2][0], k[1][1] - k[2][1]],
    ];
    let cy = [
        [hx[0][0] + hx[2][0], hx[0][1] + hx[2][1]],
        [hx[0][0] + hx[1][0], hx[0][1] + hx[1][1]],
        [hx[1][0] + hx[2][0], hx[1][1] + hx[2][1]],
    ];
    let cx = [
        [-hy2[0], -hy2[1]],
        [-hy1[0], -hy1[1]],
        [-(hy1[0] + hy2[0]), -(hy1[1] + hy2[1])],
    ];
    (cw, cx, cy)
}

/// The vectors the nodal forces and moments of a triangle combine (see `tri_kernel`).
struct NodeForce<S> {
    p1: V3<S>,
    p2: V3<S>,
    fb: V3<S>,
    fc: V3<S>,
    mb: V3<S>,
    mc: V3<S>,
    mk: V3<S>,
    e1: V3<S>,
    e2: V3<S>,
    e3: V3<S>,
    aq: [S; 2],
}

impl<S: Real> NodeForce<S> {
    /// Force and moment of the node with reference gradients (bx0, by0), current
    /// gradients (bx, by) and shear-operator rows cw, cx, cy.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    fn at(&self, (bx0, by0, bx, by, cw, cx, cy): (S, S, S, S, [S; 2], [S; 2], [S; 2])) -> [S; 6] {
        let aq = self.aq;
        let f = self
            .p1
            .scale(bx0)
            .plus(self.p2.scale(by0))
            .plus(self.fb.scale(bx))
            .plus(self.fc.scale(by))
            .plus(self.e3.scale(aq[0] * cw[0] + aq[1] * cw[1]));
        let m = self
            .mb
            .scale(bx)
            .plus(self.mc.scale(by))
            .plus(self.e1.scale(aq[0] * cx[0] + aq[1] * cx[1]))
            .plus(self.e2.scale(aq[0] * cy[0] + aq[1] * cy[1]))
            .plus(self.mk);
        [f.x, f.y, f.z, m.x, m.y, m.z]
    }
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
    /// Characteristic length L_e of the current configuration.
    pub length: S,
    /// Current area / initial area (collapse check by the caller).
    pub ratio: S,
}

/// Internal forces of a triangle: writes its three slots (global force, moment) to
/// `out` and, when the material has Kelvin damping, the Kelvin part of the same forces
/// to `out_d` (for the energy ledger: docs/theory.md section 6; untouched otherwise).
/// `KELVIN` false (a chunk that has no Kelvin slots) compiles that part out, so an
/// undamped body runs the same code as before the Kelvin slots existed.
///
/// Straight-line code, no per-node accumulation arrays: the compiler keeps everything in
/// registers (with AVX-512 enabled it otherwise turns such loops into masked
/// gathers/scatters on the stack).
#[inline(always)]
pub fn tri_kernel<S: Real, const KELVIN: bool>(
    k: &Consts<S>,
    e: &TriIn<S>,
    h: S,
    st: &mut ShellL<S>,
    out: &mut [[S; 6]; 3],
    out_d: &mut [[S; 6]; 3],
) -> KernelOut<S> {
    let zero = S::splat(0.0);
    let half = S::splat(0.5);
    let one = S::splat(1.0);
    let (x, v, w) = (&e.x, &e.v, &e.w);

    // co-rotational frame: e1 along edge 1-2, e3 normal; local nodes (0,0), (a,0), (c,d)
    let r2 = x[1].minus(x[0]);
    let r3 = x[2].minus(x[0]);
    let r23 = x[2].minus(x[1]);
    let n = r2.cross(r3);
    let two_area = n.norm_squared().sqrt();
    let e3 = n.scale(one / two_area);
    let l2sq = r2.norm_squared();
    let a = l2sq.sqrt();
    let e1 = r2.scale(one / a);
    let e2 = e3.cross(e1);
    let c = r3.dot(e1);
    let d = r3.dot(e2);
    let area = half * two_area;

    // membrane, total Lagrangian: f_I = p1 bx0_I + p2 by0_I
    let (e_mem, p1, p2, pd) = membrane_stress(
        &k.membrane,
        k.alpha,
        &e.bx0,
        &e.by0,
        e.area0,
        &[zero; 3],
        x,
        v,
    );

    // current gradients and the assumed-shear operator
    let (bx, by) = tri_gradients(a, c, d);
    let (cw, cx, cy) = tri_shear_operator(a, c, d);

    // local rates
    let vz = [v[0].dot(e3), v[1].dot(e3), v[2].dot(e3)];
    let wx = [w[0].dot(e1), w[1].dot(e1), w[2].dot(e1)];
    let wy = [w[0].dot(e2), w[1].dot(e2), w[2].dot(e2)];
    let wz = w[0].plus(w[1]).plus(w[2]).dot(e3);
    let sbx = v[0].scale(bx[0]).plus(v[1].scale(bx[1])); // bx[2] = 0
    let sby = v[0]
        .scale(by[0])
        .plus(v[1].scale(by[1]))
        .plus(v[2].scale(by[2]));
    let spin = sbx.dot(e2) - sby.dot(e1);
    let kr = [
        bx[0] * wy[0] + bx[1] * wy[1],
        -(by[0] * wx[0] + by[1] * wx[1] + by[2] * wx[2]),
        by[0] * wy[0] + by[1] * wy[1] + by[2] * wy[2] - (bx[0] * wx[0] + bx[1] * wx[1]),
    ];
    let g = [
        cw[0][0] * vz[0]
            + cx[0][0] * wx[0]
            + cy[0][0] * wy[0]
            + (cw[1][0] * vz[1] + cx[1][0] * wx[1] + cy[1][0] * wy[1])
            + (cw[2][0] * vz[2] + cx[2][0] * wx[2] + cy[2][0] * wy[2]),
        cw[0][1] * vz[0]
            + cx[0][1] * wx[0]
            + cy[0][1] * wy[0]
            + (cw[1][1] * vz[1] + cx[1][1] * wx[1] + cy[1][1] * wy[1])
            + (cw[2][1] * vz[2] + cx[2][1] * wx[2] + cy[2][1] * wy[2]),
    ];
    let drill_rate = wz * S::splat(1.0 / 3.0) - half * spin;

    let (e_pl, mm, qq, (md, qd)) = plate_update(k, area, kr, g, drill_rate, h, st);

    // nodal forces and moments
    let td = area * st.drill;
    let td_half = half * td;
    let fb = e2.scale(-td_half); // coefficient of bx_I
    let fc = e1.scale(td_half); // coefficient of by_I
    let mb = e2.scale(area * mm[0]).minus(e1.scale(area * mm[2]));
    let mc = e2.scale(area * mm[2]).minus(e1.scale(area * mm[1]));
    let mk = e3.scale(td * S::splat(1.0 / 3.0));
    let (aq0, aq1) = (area * qq[0], area * qq[1]);
    // f_I = p1 bx0_I + p2 by0_I + fb bx_I + fc by_I + e3 A (q . cw_I)
    // m_I = mb bx_I + mc by_I + e1 A (q . cx_I) + e2 A (q . cy_I) + mk
    let g = NodeForce {
        p1,
        p2,
        fb,
        fc,
        mb,
        mc,
        mk,
        e1,
        e2,
        e3,
        aq: [aq0, aq1],
    };
    out[0] = g.at((e.bx0[0], e.by0[0], bx[0], by[0], cw[0], cx[0], cy[0]));
    out[1] = g.at((e.bx0[1], e.by0[1], bx[1], by[1], cw[1], cx[1], cy[1]));
    out[2] = g.at((e.bx0[2], e.by0[2], bx[2], by[2], cw[2], cx[2], cy[2]));
    if KELVIN && k.alpha > 0.0 {
        // the same combination of the Kelvin resultants alone (drilling is not damped)
        let z3 = V3::zero();
        let gd = NodeForce {
            p1: pd[0],
            p2: pd[1],
            fb: z3,
            fc: z3,
            mb: e2.scale(area * md[0]).minus(e1.scale(area * md[2])),
            mc: e2.scale(area * md[2]).minus(e1.scale(area * md[1])),
            mk: z3,
            e1,
            e2,
            e3,
            aq: [area * qd[0], area * qd[1]],
        };
        out_d[0] = gd.at((e.bx0[0], e.by0[0], bx[0], by[0], cw[0], cx[0], cy[0]));
        out_d[1] = gd.at((e.bx0[1], e.by0[1], bx[1], by[1], cw[1], cx[1], cy[1]));
        out_d[2] = gd.at((e.bx0[2], e.by0[2], bx[2], by[2], cw[2], cx[2], cy[2]));
    }
    let longest = l2sq.max(r3.norm_squared()).max(r23.norm_squared()).sqrt();
    KernelOut {
        internal: e_mem + e_pl,
        length: two_area / longest,
        ratio: area / e.area0,
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
