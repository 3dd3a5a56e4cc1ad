//! 4-node Belytschko–Lin–Tsay quadrilateral, one-point, co-rotational, with
//! stiffness-type hourglass control.
//!
//! Membrane: total-Lagrangian at the centroid (see `membrane`) plus in-plane hourglass
//! q = sum_I gamma_I x_I projected on the element plane (zero for any affine motion).
//! Plate: BLT bending and centroid shear in the co-rotational frame of the diagonals,
//! with rate-form hourglass resultants for w and theta. Warped quads are refused at input
//! (`mesh::WARP_LIMIT`); no warping correction is applied.

use super::membrane::{gradient, green, membrane_forces};
use super::plate::{plate_forces, Consts, LocalRates, PlateKin, ShellL};
use super::real::{Real, V3};
use super::reference::{quad_gradients, Frame};
use super::tri::KernelOut;
use super::Stabilization;
use crate::material::Section;
use crate::Vec3;
use serde::{Deserialize, Serialize};

/// Hourglass base vector h = (1, -1, 1, -1).
const HG: [f64; 4] = [1.0, -1.0, 1.0, -1.0];

/// Reference data of one quad.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct QuadElem {
    pub nodes: [u32; 4],
    pub bx0: [f64; 4],
    pub by0: [f64; 4],
    /// Hourglass shape vector gamma_I = (h_I - (h.X) bx_I - (h.Y) by_I) / 4.
    pub gamma: [f64; 4],
    pub area0: f64,
    /// Green strain of the reference configuration (subtracted: stress-free start).
    pub e0: [f64; 3],
    /// Hourglass stiffnesses: in-plane [N/m], w [N/m], rotation [N m].
    pub k_m: f64,
    pub k_w: f64,
    pub k_th: f64,
}

impl QuadElem {
    pub fn new(nodes: [u32; 4], x: &[Vec3; 4], sec: &Section, stab: &Stabilization) -> Self {
        let (fr, c) = Frame::quad(x);
        let xl = x.map(|p| (p - c).dot(&fr.e1));
        let yl = x.map(|p| (p - c).dot(&fr.e2));
        let (bx0, by0, area0) = quad_gradients(xl, yl);
        let hx: f64 = (0..4).map(|i| HG[i] * xl[i]).sum();
        let hy: f64 = (0..4).map(|i| HG[i] * yl[i]).sum();
        let gamma = std::array::from_fn(|i| 0.25 * (HG[i] - hx * bx0[i] - hy * by0[i]));
        let (f1, f2) = gradient(x, &bx0, &by0);
        let e0 = green(&f1, &f2);
        let bb: f64 = (0..4).map(|i| bx0[i] * bx0[i] + by0[i] * by0[i]).sum();
        Self {
            nodes,
            bx0,
            by0,
            gamma,
            area0,
            e0,
            k_m: stab.hourglass_membrane * sec.membrane * area0 * bb,
            k_w: stab.hourglass_w * sec.bending * area0 * bb * bb,
            k_th: stab.hourglass_rotation * sec.bending * area0 * bb,
        }
    }
}

/// Rate-form hourglass resultants in kernel form.
#[derive(Debug, Clone, Copy)]
pub struct HgL<S> {
    pub w: S,
    pub th: [S; 2],
}

/// Inputs of the quad kernel (one element, or four in lanes).
#[derive(Debug, Clone, Copy)]
pub struct QuadIn<S> {
    pub x: [V3<S>; 4],
    pub v: [V3<S>; 4],
    pub w: [V3<S>; 4],
    pub bx0: [S; 4],
    pub by0: [S; 4],
    pub gamma: [S; 4],
    pub area0: S,
    pub e0: [S; 3],
    pub k_m: S,
    pub k_w: S,
    pub k_th: S,
    /// 1/(2 k_w), 1/(2 k_theta) (0 when the stiffness is 0).
    pub hinv_w: S,
    pub hinv_th: S,
}

/// Extra outputs of the quad kernel.
#[derive(Debug, Clone, Copy)]
pub struct QuadExtra<S> {
    pub hourglass: S,
    /// Corner orientation (positive when the corner is convex and not inverted).
    pub corners: [S; 4],
}

/// Internal forces of a quad: writes its four slots (global force, moment).
#[inline(always)]
pub fn quad_kernel<S: Real>(
    k: &Consts<S>,
    e: &QuadIn<S>,
    h: S,
    st: &mut ShellL<S>,
    hg: &mut HgL<S>,
    out: &mut [[S; 6]; 4],
) -> (KernelOut<S>, QuadExtra<S>) {
    let zero = S::splat(0.0);
    let one = S::splat(1.0);
    let quarter = S::splat(0.25);
    let x = &e.x;
    let n = x[2].minus(x[0]).cross(x[3].minus(x[1]));
    let e3 = n.scale(one / n.norm_squared().sqrt());
    let r = x[1].minus(x[0]);
    let r = r.minus(e3.scale(r.dot(e3)));
    let e1 = r.scale(one / r.norm_squared().sqrt());
    let e2 = e3.cross(e1);
    let c = x[0].plus(x[1]).plus(x[2]).plus(x[3]).scale(quarter);
    let xl: [S; 4] = std::array::from_fn(|i| x[i].minus(c).dot(e1));
    let yl: [S; 4] = std::array::from_fn(|i| x[i].minus(c).dot(e2));
    let (bx, by, area) = quad_gradients(xl, yl);
    let corners = std::array::from_fn(|i| {
        let (nx, p) = ((i + 1) % 4, (i + 3) % 4);
        (xl[nx] - xl[i]) * (yl[p] - yl[i]) - (yl[nx] - yl[i]) * (xl[p] - xl[i])
    });

    let mut fm = [V3::zero(); 4];
    let (e_mem, d_mem) = membrane_forces(
        &k.membrane,
        k.alpha,
        &e.bx0,
        &e.by0,
        e.area0,
        &e.e0,
        x,
        &e.v,
        h,
        &mut fm,
    );

    // in-plane hourglass, total form
    let g = &e.gamma;
    let mut q = V3::zero();
    for (xi, gi) in x.iter().zip(g) {
        q = q.plus(xi.scale(*gi));
    }
    let qt = q.minus(e3.scale(q.dot(e3)));
    let fq = qt.scale(e.k_m);
    let mut e_hg = S::splat(0.5) * e.k_m * qt.norm_squared();

    let loc = |p: V3<S>| [p.dot(e1), p.dot(e2), p.dot(e3)];
    let rates = LocalRates {
        v: [loc(e.v[0]), loc(e.v[1]), loc(e.v[2]), loc(e.v[3])],
        w: [loc(e.w[0]), loc(e.w[1]), loc(e.w[2]), loc(e.w[3])],
    };
    // out-of-plane and rotational hourglass, rate form
    let mut qw = zero;
    let mut qth = [zero; 2];
    for i in 0..4 {
        qw += g[i] * rates.v[i][2];
        qth[0] += g[i] * rates.w[i][0];
        qth[1] += g[i] * rates.w[i][1];
    }
    hg.w += h * e.k_w * qw;
    hg.th[0] += h * e.k_th * qth[0];
    hg.th[1] += h * e.k_th * qth[1];
    e_hg += hg.w * hg.w * e.hinv_w + (hg.th[0] * hg.th[0] + hg.th[1] * hg.th[1]) * e.hinv_th;

    let q4 = S::splat(0.25);
    let kin = PlateKin {
        bx,
        by,
        area,
        cw: std::array::from_fn(|i| [bx[i], by[i]]),
        cx: [[zero, -q4]; 4],
        cy: [[q4, zero]; 4],
    };
    let mut lo = [[zero; 6]; 4];
    let (e_pl, d_pl) = plate_forces(k, &kin, &rates, h, st, &mut lo);
    for i in 0..4 {
        lo[i][2] += g[i] * hg.w;
        lo[i][3] += g[i] * hg.th[0];
        lo[i][4] += g[i] * hg.th[1];
        let f = fm[i]
            .plus(fq.scale(g[i]))
            .plus(e1.scale(lo[i][0]))
            .plus(e2.scale(lo[i][1]))
            .plus(e3.scale(lo[i][2]));
        let m = e1
            .scale(lo[i][3])
            .plus(e2.scale(lo[i][4]))
            .plus(e3.scale(lo[i][5]));
        out[i] = [f.x, f.y, f.z, m.x, m.y, m.z];
    }
    let diag = x[2]
        .minus(x[0])
        .norm_squared()
        .max(x[3].minus(x[1]).norm_squared())
        .sqrt();
    (
        KernelOut {
            internal: e_mem + e_pl,
            damping: d_mem + d_pl,
            length: area / diag,
            ratio: area / e.area0,
        },
        QuadExtra {
            hourglass: e_hg,
            corners,
        },
    )
}
