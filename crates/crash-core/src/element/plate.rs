//! The plate part shared by both elements, in the co-rotational frame: bending and
//! transverse shear (Reissner–Mindlin) and the drilling stabilization, in rate form.
//!
//! Velocity of a fibre at height z: v = v_mid + omega x (z e3), so in local axes
//! v_x = v_x^m + z w_y, v_y = v_y^m - z w_x. Hence (one-point, at the centroid)
//!   curvature rate   k_xx = d(w_y)/dx, k_yy = -d(w_x)/dy, k_xy = d(w_y)/dy - d(w_x)/dx
//!   shear rate       g_xz = dv_z/dx + w_y,  g_yz = dv_z/dy - w_x  (element-specific operator)
//!   drilling rate    d    = mean(w_z) - (dv_y/dx - dv_x/dy)/2
//! All three vanish for any rigid velocity field, so the nodal forces below (the exact
//! transpose of these maps) are self-equilibrated: linear and angular momentum are
//! conserved to round-off.

use super::membrane::Plane;
use super::real::Real;
use super::Stabilization;
use crate::material::Section;

/// Section constants in kernel form (splatted once per body and pass).
#[derive(Debug, Clone, Copy)]
pub struct Consts<S> {
    pub membrane: Plane<S>,
    pub bending: Plane<S>,
    /// kappa G t.
    pub shear: S,
    /// Drilling stiffness r_d G t.
    pub drill: S,
    /// Kelvin alpha (0: the damping branch is skipped).
    pub alpha: f64,
    /// Energy factors: 1/(2 D (1-nu^2)), 2 nu, 2 (1+nu), 1/(2 kGt), 1/(2 k_d).
    pub bend_energy: S,
    pub two_nu: S,
    pub two_1pnu: S,
    pub half_inv_shear: S,
    pub half_inv_drill: S,
}

impl<S: Real> Consts<S> {
    pub fn new(sec: &Section, stab: &Stabilization) -> Self {
        let nu = sec.material.poisson;
        let drill = stab.drilling * sec.material.shear_modulus() * sec.thickness;
        Self {
            membrane: Plane::new(sec.membrane, nu),
            bending: Plane::new(sec.bending, nu),
            shear: S::splat(sec.shear),
            drill: S::splat(drill),
            alpha: sec.material.kelvin,
            bend_energy: S::splat(1.0 / (2.0 * sec.bending * (1.0 - nu * nu))),
            two_nu: S::splat(2.0 * nu),
            two_1pnu: S::splat(2.0 * (1.0 + nu)),
            half_inv_shear: S::splat(0.5 / sec.shear),
            half_inv_drill: S::splat(if drill > 0.0 { 0.5 / drill } else { 0.0 }),
        }
    }
}

/// Rate-form resultants of one element (or a batch), in the co-rotational frame.
#[derive(Debug, Clone, Copy)]
pub struct ShellL<S> {
    pub m: [S; 3],
    pub q: [S; 2],
    pub drill: S,
}

/// Local kinematics of an N-node element at the current configuration.
#[derive(Debug, Clone, Copy)]
pub struct PlateKin<S, const N: usize> {
    pub bx: [S; N],
    pub by: [S; N],
    pub area: S,
    /// Shear operator: g = sum_I cw[I] vz_I + cx[I] wx_I + cy[I] wy_I (2-vectors).
    pub cw: [[S; 2]; N],
    pub cx: [[S; 2]; N],
    pub cy: [[S; 2]; N],
}

/// Local nodal rates: translational velocity and angular velocity in the element frame.
#[derive(Debug, Clone, Copy)]
pub struct LocalRates<S, const N: usize> {
    pub v: [[S; 3]; N],
    pub w: [[S; 3]; N],
}

/// Update the rate-form resultants over the step `h` and add the plate part of the
/// internal forces (local axes) to `out` (per node: fx, fy, fz, mx, my, mz).
/// Returns (stored energy, Kelvin dissipation over h).
#[inline(always)]
pub fn plate_forces<S: Real, const N: usize>(
    k: &Consts<S>,
    kin: &PlateKin<S, N>,
    r: &LocalRates<S, N>,
    h: S,
    st: &mut ShellL<S>,
    out: &mut [[S; 6]; N],
) -> (S, S) {
    let (bx, by) = (&kin.bx, &kin.by);
    let zero = S::splat(0.0);
    let half = S::splat(0.5);
    let inv_n = S::splat(1.0 / N as f64);
    let mut kr = [zero; 3];
    let mut g = [zero; 2];
    let mut wz = zero;
    let mut spin = zero;
    for i in 0..N {
        let (wx, wy) = (r.w[i][0], r.w[i][1]);
        kr[0] += bx[i] * wy;
        kr[1] -= by[i] * wx;
        kr[2] += by[i] * wy - bx[i] * wx;
        let vz = r.v[i][2];
        g[0] += kin.cw[i][0] * vz + kin.cx[i][0] * wx + kin.cy[i][0] * wy;
        g[1] += kin.cw[i][1] * vz + kin.cx[i][1] * wx + kin.cy[i][1] * wy;
        wz += r.w[i][2];
        spin += bx[i] * r.v[i][1] - by[i] * r.v[i][0];
    }
    let drill_rate = wz * inv_n - half * spin;

    let dm = k.bending.apply(kr);
    for (m, d) in st.m.iter_mut().zip(dm) {
        *m += h * d;
    }
    st.q[0] += h * k.shear * g[0];
    st.q[1] += h * k.shear * g[1];
    st.drill += h * k.drill * drill_rate;

    let m0 = st.m;
    let energy = kin.area
        * ((m0[0] * m0[0] + m0[1] * m0[1] - k.two_nu * m0[0] * m0[1] + k.two_1pnu * m0[2] * m0[2])
            * k.bend_energy
            + (st.q[0] * st.q[0] + st.q[1] * st.q[1]) * k.half_inv_shear
            + st.drill * st.drill * k.half_inv_drill);

    // Kelvin damping: resultants from the strain rate (skipped when alpha = 0).
    let (mut m, mut q) = (st.m, st.q);
    let mut diss = zero;
    if k.alpha > 0.0 {
        let a = S::splat(k.alpha);
        let md = k.bending.apply_scaled(a, kr);
        let qd = [a * k.shear * g[0], a * k.shear * g[1]];
        diss = h
            * kin.area
            * (md[0] * kr[0] + md[1] * kr[1] + md[2] * kr[2] + qd[0] * g[0] + qd[1] * g[1]);
        for (mc, d) in m.iter_mut().zip(md) {
            *mc += d;
        }
        q[0] += qd[0];
        q[1] += qd[1];
    }

    let a = kin.area;
    let td = a * st.drill;
    let td_n = td * inv_n;
    let td_half = half * td;
    for i in 0..N {
        let o = &mut out[i];
        // bending: power A (Mxx kxx + Myy kyy + Mxy kxy)
        o[3] += a * (-(by[i] * m[1]) - bx[i] * m[2]);
        o[4] += a * (bx[i] * m[0] + by[i] * m[2]);
        // shear: power A (Qx gx + Qy gy)
        o[2] += a * (q[0] * kin.cw[i][0] + q[1] * kin.cw[i][1]);
        o[3] += a * (q[0] * kin.cx[i][0] + q[1] * kin.cx[i][1]);
        o[4] += a * (q[0] * kin.cy[i][0] + q[1] * kin.cy[i][1]);
        // drilling: power A tau d
        o[5] += td_n;
        o[0] += td_half * by[i];
        o[1] -= td_half * bx[i];
    }
    (energy, diss)
}
