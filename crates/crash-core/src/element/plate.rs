//! The plate part shared by both elements, in the co-rotational frame: bending and
//! transverse shear (Reissner–Mindlin) and the drilling stabilization, in rate form.
//! Each element kernel computes the centroid rates below and the nodal forces as the
//! exact transpose of its own rate operator; the resultant update is shared.
//!
//! Velocity of a fibre at height z: v = v_mid + omega x (z e3), so in local axes
//! v_x = v_x^m + z w_y, v_y = v_y^m - z w_x. Hence (one-point, at the centroid)
//!   curvature rate   k_xx = d(w_y)/dx, k_yy = -d(w_x)/dy, k_xy = d(w_y)/dy - d(w_x)/dx
//!   shear rate       g_xz = dv_z/dx + w_y,  g_yz = dv_z/dy - w_x  (element-specific operator)
//!   drilling rate    d    = mean(w_z) - (dv_y/dx - dv_x/dy)/2
//! All three vanish for any rigid velocity field, so the nodal forces (the exact
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
    /// Hourglass stiffness factors of the quad: r_m C, r_w D, r_th D
    /// (`quad::hourglass_stiffness`).
    pub hourglass: [S; 3],
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
            hourglass: [
                S::splat(stab.hourglass_membrane * sec.membrane),
                S::splat(stab.hourglass_w * sec.bending),
                S::splat(stab.hourglass_rotation * sec.bending),
            ],
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

/// Update the rate-form resultants over the step `h` from the centroid rates (curvature
/// kr, transverse shear g, drilling), for an element of current area `area`. Returns
/// (stored energy, moments, shear forces, their Kelvin parts): the moments and shear
/// forces include the Kelvin damping part (they enter the nodal forces; the state does
/// not), which is returned on its own too (zero when alpha = 0) for the energy ledger.
#[allow(clippy::type_complexity)]
#[inline(always)]
pub fn plate_update<S: Real>(
    k: &Consts<S>,
    area: S,
    kr: [S; 3],
    g: [S; 2],
    drill_rate: S,
    h: S,
    st: &mut ShellL<S>,
) -> (S, [S; 3], [S; 2], ([S; 3], [S; 2])) {
    let dm = k.bending.apply(kr);
    st.m[0] += h * dm[0];
    st.m[1] += h * dm[1];
    st.m[2] += h * dm[2];
    st.q[0] += h * k.shear * g[0];
    st.q[1] += h * k.shear * g[1];
    st.drill += h * k.drill * drill_rate;
    let m0 = st.m;
    let energy = area
        * ((m0[0] * m0[0] + m0[1] * m0[1] - k.two_nu * m0[0] * m0[1] + k.two_1pnu * m0[2] * m0[2])
            * k.bend_energy
            + (st.q[0] * st.q[0] + st.q[1] * st.q[1]) * k.half_inv_shear
            + st.drill * st.drill * k.half_inv_drill);
    let (mut m, mut q) = (st.m, st.q);
    let zero = S::splat(0.0);
    let mut kelvin = ([zero; 3], [zero; 2]);
    if k.alpha > 0.0 {
        let a = S::splat(k.alpha);
        let md = k.bending.apply_scaled(a, kr);
        let qd = [a * k.shear * g[0], a * k.shear * g[1]];
        m[0] += md[0];
        m[1] += md[1];
        m[2] += md[2];
        q[0] += qd[0];
        q[1] += qd[1];
        kelvin = (md, qd);
    }
    (energy, m, q, kelvin)
}
