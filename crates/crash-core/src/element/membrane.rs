//! Membrane part of both elements: total-Lagrangian St. Venant–Kirchhoff, one point.
//!
//! F = sum_I x_I (x) grad0 N_I (3x2), E = (F^T F - I)/2 - E_0, S = C E, f_I = A0 F S grad0 N_I.
//! Frame-free: exactly zero strain under any rigid motion, hyperelastic (the stored
//! energy A0 t S:E/2 is exact), and F S F^T is symmetric, so the membrane forces conserve
//! angular momentum to round-off.

use super::real::{Real, V3};
use crate::Vec3;

/// Plane-stress constants in kernel form.
#[derive(Debug, Clone, Copy)]
pub struct Plane<S> {
    /// Stiffness scale (t E/(1-nu^2) for membrane, D for bending).
    pub k: S,
    pub nu: S,
    /// (1 - nu) / 2.
    pub half_1mnu: S,
}

impl<S: Real> Plane<S> {
    pub fn new(k: f64, nu: f64) -> Self {
        Self {
            k: S::splat(k),
            nu: S::splat(nu),
            half_1mnu: S::splat(0.5 * (1.0 - nu)),
        }
    }

    /// C e for engineering strain (xx, yy, 2xy), scaled by k.
    #[inline(always)]
    pub fn apply(&self, e: [S; 3]) -> [S; 3] {
        [
            self.k * (e[0] + self.nu * e[1]),
            self.k * (self.nu * e[0] + e[1]),
            self.k * self.half_1mnu * e[2],
        ]
    }

    /// Same with an extra factor (Kelvin damping alpha).
    #[inline(always)]
    pub fn apply_scaled(&self, f: S, e: [S; 3]) -> [S; 3] {
        let s = self.apply(e);
        [f * s[0], f * s[1], f * s[2]]
    }
}

/// Green strain (xx, yy, 2xy) of the deformation gradient columns f1, f2.
#[inline(always)]
pub fn green_s<S: Real>(f1: V3<S>, f2: V3<S>) -> [S; 3] {
    let half = S::splat(0.5);
    let one = S::splat(1.0);
    [
        half * (f1.dot(f1) - one),
        half * (f2.dot(f2) - one),
        f1.dot(f2),
    ]
}

/// Green strain for nalgebra vectors (setup and output).
pub fn green(f1: &Vec3, f2: &Vec3) -> [f64; 3] {
    green_s(V3::new(f1.x, f1.y, f1.z), V3::new(f2.x, f2.y, f2.z))
}

/// Deformation gradient columns from nodal positions and reference gradients.
pub fn gradient<const N: usize>(x: &[Vec3; N], bx: &[f64; N], by: &[f64; N]) -> (Vec3, Vec3) {
    let mut f1 = Vec3::zeros();
    let mut f2 = Vec3::zeros();
    for i in 0..N {
        f1 += x[i] * bx[i];
        f2 += x[i] * by[i];
    }
    (f1, f2)
}

#[inline(always)]
fn gradient_s<S: Real, const N: usize>(x: &[V3<S>; N], bx: &[S; N], by: &[S; N]) -> (V3<S>, V3<S>) {
    let mut f1 = V3::zero();
    let mut f2 = V3::zero();
    for i in 0..N {
        f1 = f1.plus(x[i].scale(bx[i]));
        f2 = f2.plus(x[i].scale(by[i]));
    }
    (f1, f2)
}

/// Membrane stress of one element (or a batch): returns (stored energy, p1, p2, the
/// Kelvin part of p1 and p2) with the nodal forces f_I = p1 bx_I + p2 by_I
/// (p1, p2 = A0 F S e1, A0 F S e2, S including the Kelvin stress S_d when alpha > 0;
/// the Kelvin part A0 F S_d e1, A0 F S_d e2 is zero when alpha = 0). The Kelvin part
/// is for the energy ledger only (docs/theory.md section 6): the forces use p1, p2.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
#[inline(always)]
pub fn membrane_stress<S: Real, const N: usize>(
    c: &Plane<S>,
    alpha: f64,
    bx: &[S; N],
    by: &[S; N],
    area0: S,
    e0: &[S; 3],
    x: &[V3<S>; N],
    v: &[V3<S>; N],
) -> (S, V3<S>, V3<S>, [V3<S>; 2]) {
    let (f1, f2) = gradient_s(x, bx, by);
    let g = green_s(f1, f2);
    let e = [g[0] - e0[0], g[1] - e0[1], g[2] - e0[2]];
    let mut s = c.apply(e);
    let energy = S::splat(0.5) * area0 * (s[0] * e[0] + s[1] * e[1] + s[2] * e[2]);
    let mut pd = [V3::zero(); 2];
    if alpha > 0.0 {
        let (d1, d2) = gradient_s(v, bx, by);
        let ed = [f1.dot(d1), f2.dot(d2), f1.dot(d2) + d1.dot(f2)];
        let sd = c.apply_scaled(S::splat(alpha), ed);
        pd = [
            f1.scale(sd[0]).plus(f2.scale(sd[2])).scale(area0),
            f1.scale(sd[2]).plus(f2.scale(sd[1])).scale(area0),
        ];
        s[0] += sd[0];
        s[1] += sd[1];
        s[2] += sd[2];
    }
    let p1 = f1.scale(s[0]).plus(f2.scale(s[2])).scale(area0);
    let p2 = f1.scale(s[2]).plus(f2.scale(s[1])).scale(area0);
    (energy, p1, p2, pd)
}
