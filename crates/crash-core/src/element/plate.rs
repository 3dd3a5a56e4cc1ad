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

use super::{ElemEnergy, ShellState};
use crate::material::Section;

/// Local kinematics of an N-node element at the current configuration.
#[derive(Debug, Clone, Copy)]
pub struct PlateKin<const N: usize> {
    pub bx: [f64; N],
    pub by: [f64; N],
    pub area: f64,
    /// Shear operator: g = sum_I cw[I] vz_I + cx[I] wx_I + cy[I] wy_I (2-vectors).
    pub cw: [[f64; 2]; N],
    pub cx: [[f64; 2]; N],
    pub cy: [[f64; 2]; N],
}

/// Local nodal rates: translational velocity and angular velocity in the element frame.
#[derive(Debug, Clone, Copy)]
pub struct LocalRates<const N: usize> {
    pub v: [[f64; 3]; N],
    pub w: [[f64; 3]; N],
}

/// Update the rate-form resultants over the step `h` and add the plate part of the
/// internal forces (local axes) to `out` (per node: fx, fy, fz, mx, my, mz).
#[inline(always)]
pub fn plate_forces<const N: usize>(
    sec: &Section,
    drill_k: f64,
    kin: &PlateKin<N>,
    r: &LocalRates<N>,
    h: f64,
    st: &mut ShellState,
    out: &mut [[f64; 6]; N],
    en: &mut ElemEnergy,
) {
    let (bx, by) = (&kin.bx, &kin.by);
    let inv_n = 1.0 / N as f64;
    let mut k = [0.0; 3];
    let mut g = [0.0; 2];
    let mut wz = 0.0;
    let mut spin = 0.0;
    for i in 0..N {
        let (wx, wy) = (r.w[i][0], r.w[i][1]);
        k[0] += bx[i] * wy;
        k[1] -= by[i] * wx;
        k[2] += by[i] * wy - bx[i] * wx;
        let vz = r.v[i][2];
        g[0] += kin.cw[i][0] * vz + kin.cx[i][0] * wx + kin.cy[i][0] * wy;
        g[1] += kin.cw[i][1] * vz + kin.cx[i][1] * wx + kin.cy[i][1] * wy;
        wz += r.w[i][2];
        spin += bx[i] * r.v[i][1] - by[i] * r.v[i][0];
    }
    let drill_rate = wz * inv_n - 0.5 * spin;

    // Elastic resultants: rate form in the co-rotational frame.
    let dm = sec.plane(sec.bending, k);
    for c in 0..3 {
        st.m[c] += h * dm[c];
    }
    st.q[0] += h * sec.shear * g[0];
    st.q[1] += h * sec.shear * g[1];
    st.drill += h * drill_k * drill_rate;

    en.internal += kin.area
        * (sec.plane_energy(sec.bending, st.m)
            + 0.5 * (st.q[0] * st.q[0] + st.q[1] * st.q[1]) / sec.shear
            + if drill_k > 0.0 {
                0.5 * st.drill * st.drill / drill_k
            } else {
                0.0
            });

    // Kelvin damping: resultants from the strain rate (costs nothing when alpha = 0).
    let (mut m, mut q) = (st.m, st.q);
    let alpha = sec.material.kelvin;
    if alpha > 0.0 {
        let md = sec.plane(alpha * sec.bending, k);
        let qd = [alpha * sec.shear * g[0], alpha * sec.shear * g[1]];
        en.damping += h
            * kin.area
            * (md[0] * k[0] + md[1] * k[1] + md[2] * k[2] + qd[0] * g[0] + qd[1] * g[1]);
        for c in 0..3 {
            m[c] += md[c];
        }
        q[0] += qd[0];
        q[1] += qd[1];
    }

    let a = kin.area;
    let td = a * st.drill;
    for i in 0..N {
        let o = &mut out[i];
        // bending: power A (Mxx kxx + Myy kyy + Mxy kxy)
        o[3] += a * (-by[i] * m[1] - bx[i] * m[2]);
        o[4] += a * (bx[i] * m[0] + by[i] * m[2]);
        // shear: power A (Qx gx + Qy gy)
        o[2] += a * (q[0] * kin.cw[i][0] + q[1] * kin.cw[i][1]);
        o[3] += a * (q[0] * kin.cx[i][0] + q[1] * kin.cx[i][1]);
        o[4] += a * (q[0] * kin.cy[i][0] + q[1] * kin.cy[i][1]);
        // drilling: power A tau d
        o[5] += td * inv_n;
        o[0] += 0.5 * td * by[i];
        o[1] -= 0.5 * td * bx[i];
    }
}
