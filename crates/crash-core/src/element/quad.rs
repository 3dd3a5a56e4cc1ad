//! 4-node Belytschko–Lin–Tsay quadrilateral, one-point, co-rotational, with
//! stiffness-type hourglass control.
//!
//! Membrane: total-Lagrangian at the centroid (see `membrane`) plus in-plane hourglass
//! q = sum_I gamma_I x_I projected on the element plane (zero for any affine motion).
//! Plate: BLT bending and centroid shear in the co-rotational frame of the diagonals,
//! with rate-form hourglass resultants for w and theta. Warped quads are refused at input
//! (`mesh::WARP_LIMIT`); no warping correction is applied.

use super::membrane::{gradient, green, membrane_forces};
use super::plate::{plate_forces, LocalRates, PlateKin};
use super::reference::{quad_gradients, Frame};
use super::{
    ElemEnergy, ElemFailure, HourglassState, ShellState, Slot, Stabilization, COLLAPSE_RATIO,
};
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

/// Internal forces of one quad. Writes its four slots; returns the characteristic
/// length L_e = A / longest diagonal of the current configuration.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn quad_forces(
    sec: &Section,
    stab: &Stabilization,
    el: &QuadElem,
    x: &[Vec3; 4],
    v: &[Vec3; 4],
    w: &[Vec3; 4],
    h: f64,
    st: &mut ShellState,
    hg: &mut HourglassState,
    out: &mut [Slot; 4],
    en: &mut ElemEnergy,
) -> Result<f64, ElemFailure> {
    let (fr, c) = Frame::quad(x);
    let xl = x.map(|p| (p - c).dot(&fr.e1));
    let yl = x.map(|p| (p - c).dot(&fr.e2));
    let (bx, by, area) = quad_gradients(xl, yl);
    let ratio = area / el.area0;
    if !(ratio >= COLLAPSE_RATIO) {
        return Err(ElemFailure::Collapsed { ratio });
    }
    for k in 0..4 {
        let (n, p) = ((k + 1) % 4, (k + 3) % 4);
        let cross = (xl[n] - xl[k]) * (yl[p] - yl[k]) - (yl[n] - yl[k]) * (xl[p] - xl[k]);
        if cross <= 0.0 {
            return Err(ElemFailure::Inverted { corner: k });
        }
    }
    let mut fm = [Vec3::zeros(); 4];
    membrane_forces(sec, &el.bx0, &el.by0, el.area0, &el.e0, x, v, h, &mut fm, en);

    // in-plane hourglass, total form
    let g = &el.gamma;
    let mut q = Vec3::zeros();
    for i in 0..4 {
        q += x[i] * g[i];
    }
    let qt = (q - fr.e3 * q.dot(&fr.e3)) * el.k_m;
    if el.k_m > 0.0 {
        en.hourglass += 0.5 * qt.norm_squared() / el.k_m;
    }

    let rates = LocalRates {
        v: [
            fr.local(&v[0]),
            fr.local(&v[1]),
            fr.local(&v[2]),
            fr.local(&v[3]),
        ],
        w: [
            fr.local(&w[0]),
            fr.local(&w[1]),
            fr.local(&w[2]),
            fr.local(&w[3]),
        ],
    };
    // out-of-plane and rotational hourglass, rate form
    let mut qw = 0.0;
    let mut qth = [0.0; 2];
    for i in 0..4 {
        qw += g[i] * rates.v[i][2];
        qth[0] += g[i] * rates.w[i][0];
        qth[1] += g[i] * rates.w[i][1];
    }
    hg.w += h * el.k_w * qw;
    hg.th[0] += h * el.k_th * qth[0];
    hg.th[1] += h * el.k_th * qth[1];
    if el.k_w > 0.0 {
        en.hourglass += 0.5 * hg.w * hg.w / el.k_w;
    }
    if el.k_th > 0.0 {
        en.hourglass += 0.5 * (hg.th[0] * hg.th[0] + hg.th[1] * hg.th[1]) / el.k_th;
    }

    let kin = PlateKin {
        bx,
        by,
        area,
        cw: std::array::from_fn(|i| [bx[i], by[i]]),
        cx: [[0.0, -0.25]; 4],
        cy: [[0.25, 0.0]; 4],
    };
    let mut loc = [[0.0; 6]; 4];
    let drill_k = stab.drilling * sec.material.shear_modulus() * sec.thickness;
    plate_forces(sec, drill_k, &kin, &rates, h, st, &mut loc, en);
    for i in 0..4 {
        loc[i][2] += g[i] * hg.w;
        loc[i][3] += g[i] * hg.th[0];
        loc[i][4] += g[i] * hg.th[1];
        let f = fm[i] + qt * g[i] + fr.global([loc[i][0], loc[i][1], loc[i][2]]);
        let m = fr.global([loc[i][3], loc[i][4], loc[i][5]]);
        out[i] = [f.x, f.y, f.z, m.x, m.y, m.z];
    }
    let diag = (x[2] - x[0])
        .norm_squared()
        .max((x[3] - x[1]).norm_squared())
        .sqrt();
    Ok(area / diag)
}
