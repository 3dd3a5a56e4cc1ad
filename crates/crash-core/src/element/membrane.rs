//! Membrane part of both elements: total-Lagrangian St. Venant–Kirchhoff, one point.
//!
//! F = sum_I x_I (x) grad0 N_I (3x2), E = (F^T F - I)/2 - E_0, S = C E, f_I = A0 F S grad0 N_I.
//! Frame-free: exactly zero strain under any rigid motion, hyperelastic (the stored
//! energy A0 t S:E/2 is exact), and F S F^T is symmetric, so the membrane forces conserve
//! angular momentum to round-off.

use super::ElemEnergy;
use crate::material::Section;
use crate::Vec3;

/// Green strain (xx, yy, 2xy) of the deformation gradient columns f1, f2.
#[inline(always)]
pub fn green(f1: &Vec3, f2: &Vec3) -> [f64; 3] {
    [
        0.5 * (f1.dot(f1) - 1.0),
        0.5 * (f2.dot(f2) - 1.0),
        f1.dot(f2),
    ]
}

/// Deformation gradient columns from nodal positions and reference gradients.
#[inline(always)]
pub fn gradient<const N: usize>(x: &[Vec3; N], bx: &[f64; N], by: &[f64; N]) -> (Vec3, Vec3) {
    let mut f1 = Vec3::zeros();
    let mut f2 = Vec3::zeros();
    for i in 0..N {
        f1 += x[i] * bx[i];
        f2 += x[i] * by[i];
    }
    (f1, f2)
}

/// Membrane forces (global) written into `f`; adds energy and damping dissipation.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn membrane_forces<const N: usize>(
    sec: &Section,
    bx: &[f64; N],
    by: &[f64; N],
    area0: f64,
    e0: &[f64; 3],
    x: &[Vec3; N],
    v: &[Vec3; N],
    h: f64,
    f: &mut [Vec3; N],
    en: &mut ElemEnergy,
) {
    let (f1, f2) = gradient(x, bx, by);
    let g = green(&f1, &f2);
    let e = [g[0] - e0[0], g[1] - e0[1], g[2] - e0[2]];
    let mut s = sec.plane(sec.membrane, e);
    en.internal += 0.5 * area0 * (s[0] * e[0] + s[1] * e[1] + s[2] * e[2]);
    let alpha = sec.material.kelvin;
    if alpha > 0.0 {
        let (d1, d2) = gradient(v, bx, by);
        let ed = [f1.dot(&d1), f2.dot(&d2), f1.dot(&d2) + d1.dot(&f2)];
        let sd = sec.plane(alpha * sec.membrane, ed);
        en.damping += h * area0 * (sd[0] * ed[0] + sd[1] * ed[1] + sd[2] * ed[2]);
        s[0] += sd[0];
        s[1] += sd[1];
        s[2] += sd[2];
    }
    let p1 = (f1 * s[0] + f2 * s[2]) * area0;
    let p2 = (f1 * s[2] + f2 * s[1]) * area0;
    for i in 0..N {
        f[i] = p1 * bx[i] + p2 * by[i];
    }
}
