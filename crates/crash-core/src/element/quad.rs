//! 4-node Belytschko–Lin–Tsay quadrilateral, one-point, co-rotational, with
//! stiffness-type hourglass control.
//!
//! Membrane: total-Lagrangian at the centroid (see `membrane`) plus in-plane hourglass
//! q = sum_I gamma_I x_I projected on the element plane (zero for any affine motion).
//! Plate: BLT bending and centroid shear in the co-rotational frame of the diagonals,
//! with rate-form hourglass resultants for w and theta. Warped quads are refused at input
//! (`mesh::WARP_LIMIT`); no warping correction is applied.
//!
//! The kernel works with the diagonals d13 = x3 - x1, d24 = x4 - x2. The one-point
//! gradients are antisymmetric across them (b_1 = -b_3, b_2 = -b_4, for the reference
//! and the current geometry alike), so every gradient sum over the nodes is a sum of two
//! terms on diagonal differences, and every nodal force is c_I + gamma_I G with
//! c_1 = -c_3, c_2 = -c_4: the element never forms per-node local velocities, and each
//! nodal force and moment costs one scaled vector add (docs/theory.md, section 2.3).

use super::membrane::{gradient, green, green_s};
use super::plate::{plate_update, Consts, ShellL};
use super::real::{Real, V3};
use super::reference::{quad_gradients, Frame};
use super::tri::KernelOut;
use super::Stabilization;
use crate::material::Section;
use crate::Vec3;
use serde::{Deserialize, Serialize};

/// Hourglass base vector h = (1, -1, 1, -1).
const HG: [f64; 4] = [1.0, -1.0, 1.0, -1.0];

/// Reference data of one quad. What can be derived exactly from fewer numbers is (the
/// element loop streams these bytes every cycle): the gradients of nodes 1 and 2, the
/// hourglass shape vector and the hourglass stiffnesses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct QuadElem {
    pub nodes: [u32; 4],
    /// Reference gradients of nodes 3 and 4. Those of nodes 1 and 2 are their
    /// negatives, exactly (`quad_gradients`; `bx0_all`).
    pub bx0: [f64; 2],
    pub by0: [f64; 2],
    /// h.X and h.Y, the hourglass vector h = (1, -1, 1, -1) on the reference local
    /// coordinates (`hourglass_shape`).
    pub hx: f64,
    pub hy: f64,
    pub area0: f64,
    /// Green strain of the reference configuration (subtracted: stress-free start).
    pub e0: [f64; 3],
    /// sum_I (bx_I^2 + by_I^2) of the reference gradients (`hourglass_stiffness`).
    pub bb: f64,
}

impl QuadElem {
    /// Reference data (once per element at input, outside the SIMD kernels).
    #[allow(clippy::disallowed_methods)]
    pub fn new(nodes: [u32; 4], x: &[Vec3; 4]) -> Self {
        let (fr, c) = Frame::quad(x);
        let xl = x.map(|p| (p - c).dot(&fr.e1));
        let yl = x.map(|p| (p - c).dot(&fr.e2));
        let (bx0, by0, area0) = quad_gradients(xl, yl);
        let hx: f64 = (0..4).map(|i| HG[i] * xl[i]).sum();
        let hy: f64 = (0..4).map(|i| HG[i] * yl[i]).sum();
        let (f1, f2) = gradient(x, &bx0, &by0);
        let e0 = green(&f1, &f2);
        let bb: f64 = (0..4).map(|i| bx0[i] * bx0[i] + by0[i] * by0[i]).sum();
        Self {
            nodes,
            bx0: [bx0[2], bx0[3]],
            by0: [by0[2], by0[3]],
            hx,
            hy,
            area0,
            e0,
            bb,
        }
    }

    /// The reference x-gradients of the four nodes (-b3, -b4, b3, b4).
    pub fn bx0_all(&self) -> [f64; 4] {
        let [b3, b4] = self.bx0;
        [-b3, -b4, b3, b4]
    }

    /// The reference y-gradients of the four nodes.
    pub fn by0_all(&self) -> [f64; 4] {
        let [b3, b4] = self.by0;
        [-b3, -b4, b3, b4]
    }

    /// The hourglass shape vector gamma (`hourglass_shape`).
    pub fn gamma(&self) -> [f64; 4] {
        hourglass_shape(self.bx0, self.by0, self.hx, self.hy)
    }

    /// The hourglass stiffnesses k_m, k_w, k_th of this element in `sec`, `stab`.
    pub fn stiffness(&self, sec: &Section, stab: &Stabilization) -> [f64; 3] {
        hourglass_stiffness(&Consts::<f64>::new(sec, stab), self.area0, self.bb)
    }
}

/// Hourglass shape vector gamma_I = (h_I - (h.X) bx_I - (h.Y) by_I) / 4 from the
/// gradients bx, by of nodes 3 and 4 (those of 1 and 2 their negatives): the operations
/// of that formula on the four gradients, in its order, so the same bits as computing it
/// from stored gradients (negation is exact).
#[inline(always)]
pub fn hourglass_shape<S: Real>(bx: [S; 2], by: [S; 2], hx: S, hy: S) -> [S; 4] {
    let (q, one) = (S::splat(0.25), S::splat(1.0));
    [
        q * ((one - hx * -bx[0]) - hy * -by[0]),
        q * ((-one - hx * -bx[1]) - hy * -by[1]),
        q * ((one - hx * bx[0]) - hy * by[0]),
        q * ((-one - hx * bx[1]) - hy * by[1]),
    ]
}

/// Hourglass stiffnesses [k_m, k_w, k_th]: in-plane r_m C A0 bb [N/m], w r_w D A0 bb^2
/// [N/m], rotation r_th D A0 bb [N m] (C, D the section's membrane and bending
/// stiffness; `Consts::hourglass` holds r C, r D), multiplied left to right.
#[inline(always)]
pub fn hourglass_stiffness<S: Real>(k: &Consts<S>, area0: S, bb: S) -> [S; 3] {
    let [m, w, th] = k.hourglass;
    [m * area0 * bb, w * area0 * bb * bb, th * area0 * bb]
}

/// Rate-form hourglass resultants in kernel form.
#[derive(Debug, Clone, Copy)]
pub struct HgL<S> {
    pub w: S,
    pub th: [S; 2],
}

/// Inputs of the quad kernel (one element, or a batch in lanes).
#[derive(Debug, Clone, Copy)]
pub struct QuadIn<S> {
    pub x: [V3<S>; 4],
    pub v: [V3<S>; 4],
    pub w: [V3<S>; 4],
    /// Reference gradients of nodes 3 and 4: bx0[2..4], by0[2..4] (those of nodes 1
    /// and 2 are their negatives, exactly: `quad_gradients`).
    pub bx0: [S; 2],
    pub by0: [S; 2],
    pub gamma: [S; 4],
    pub area0: S,
    pub e0: [S; 3],
    pub k_m: S,
    pub k_w: S,
    pub k_th: S,
}

/// Extra outputs of the quad kernel.
#[derive(Debug, Clone, Copy)]
pub struct QuadExtra<S> {
    pub hourglass: S,
    /// Corner orientation (positive when the corner is convex and not inverted).
    pub corners: [S; 4],
}

/// c_3, c_4 of the nodal forces (f_I = c_I + gamma_I G, c_1 = -c_3, c_2 = -c_4) from the
/// membrane rows p1, p2 and the shear and drilling rows bb, cc: the same combination for
/// the whole forces and for their Kelvin part.
#[inline(always)]
fn corner_terms<S: Real>(
    e: &QuadIn<S>,
    [p1, p2, bb, cc]: [V3<S>; 4],
    bx: &[S; 2],
    by: &[S; 2],
) -> [V3<S>; 2] {
    // written out, no closure: `std::array::from_fn`'s closure was not inlined into the
    // `#[target_feature]` entry point, so each vector operation in it became a call
    // passing vectors through memory (docs/performance-history.md, "The quad kernel on AMD
    // Zen 4")
    [
        p1.scale(e.bx0[0])
            .plus(p2.scale(e.by0[0]))
            .plus(bb.scale(bx[0]))
            .plus(cc.scale(by[0])),
        p1.scale(e.bx0[1])
            .plus(p2.scale(e.by0[1]))
            .plus(bb.scale(bx[1]))
            .plus(cc.scale(by[1])),
    ]
}

/// u_3, u_4 of the nodal moments (u_1 = -u_3, u_2 = -u_4) from the bending rows mb, mc.
#[inline(always)]
fn moment_terms<S: Real>(mb: V3<S>, mc: V3<S>, bx: &[S; 2], by: &[S; 2]) -> [V3<S>; 2] {
    // written out, not `std::array::from_fn` (see `corner_terms`)
    [
        mb.scale(bx[0]).plus(mc.scale(by[0])),
        mb.scale(bx[1]).plus(mc.scale(by[1])),
    ]
}

/// Internal forces of a quad: writes its four slots (global force, moment) to `out`
/// and, when the material has Kelvin damping, the Kelvin part of the same forces to
/// `out_d` (for the energy ledger: docs/theory.md section 6; untouched otherwise);
/// `KELVIN` false compiles that part out (as `tri_kernel`).
#[inline(always)]
pub fn quad_kernel<S: Real, const KELVIN: bool>(
    k: &Consts<S>,
    e: &QuadIn<S>,
    h: S,
    st: &mut ShellL<S>,
    hg: &mut HgL<S>,
    out: &mut [[S; 6]; 4],
    out_d: &mut [[S; 6]; 4],
) -> (KernelOut<S>, QuadExtra<S>) {
    let zero = S::splat(0.0);
    let one = S::splat(1.0);
    let half = S::splat(0.5);
    let quarter = S::splat(0.25);
    let x = &e.x;

    // co-rotational frame: e3 normal to the diagonals, e1 along edge 1-2 in the plane
    let d13 = x[2].minus(x[0]);
    let d24 = x[3].minus(x[1]);
    let n = d13.cross(d24);
    let two_area = n.norm_squared().sqrt(); // = x31 y42 - x42 y31
    let e3 = n.scale(one / two_area);
    let r = x[1].minus(x[0]);
    let r = r.minus(e3.scale(r.dot(e3)));
    let l12 = r.norm_squared().sqrt();
    let e1 = r.scale(one / l12);
    let e2 = e3.cross(e1);
    let area = half * two_area;

    // local diagonals; current gradients of nodes 3, 4 (nodes 1, 2: the negatives)
    let (x31, y31) = (d13.dot(e1), d13.dot(e2));
    let (x42, y42) = (d24.dot(e1), d24.dot(e2));
    let inv = one / two_area;
    let bx = [y42 * inv, -(y31 * inv)];
    let by = [-(x42 * inv), x31 * inv];
    // corner orientation with local nodes 1 = (0, 0), 2 = (l12, 0), 3 = (x31, y31),
    // 4 = (l12 + x42, y42)
    let (ax, ay) = (l12 + x42 - x31, y42 - y31);
    let corners = [
        l12 * y42,
        l12 * y31,
        -(ax * y31) - ay * (l12 - x31),
        (l12 + x42) * ay - y42 * ax,
    ];

    // membrane, total Lagrangian: F = sum_I x_I b0_I = b0_3 d13 + b0_4 d24
    let f1 = d13.scale(e.bx0[0]).plus(d24.scale(e.bx0[1]));
    let f2 = d13.scale(e.by0[0]).plus(d24.scale(e.by0[1]));
    let g = green_s(f1, f2);
    let es = [g[0] - e.e0[0], g[1] - e.e0[1], g[2] - e.e0[2]];
    let mut s = k.membrane.apply(es);
    let e_mem = half * e.area0 * (s[0] * es[0] + s[1] * es[1] + s[2] * es[2]);
    let mut sd = [zero; 3];
    if k.alpha > 0.0 {
        let dv13 = e.v[2].minus(e.v[0]);
        let dv24 = e.v[3].minus(e.v[1]);
        let d1 = dv13.scale(e.bx0[0]).plus(dv24.scale(e.bx0[1]));
        let d2 = dv13.scale(e.by0[0]).plus(dv24.scale(e.by0[1]));
        let ed = [f1.dot(d1), f2.dot(d2), f1.dot(d2) + d1.dot(f2)];
        sd = k.membrane.apply_scaled(S::splat(k.alpha), ed);
        s[0] += sd[0];
        s[1] += sd[1];
        s[2] += sd[2];
    }
    let p1 = f1.scale(s[0]).plus(f2.scale(s[2])).scale(e.area0);
    let p2 = f1.scale(s[2]).plus(f2.scale(s[1])).scale(e.area0);

    // in-plane hourglass, total form
    let gm = &e.gamma;
    let q = x[0]
        .scale(gm[0])
        .plus(x[1].scale(gm[1]))
        .plus(x[2].scale(gm[2]))
        .plus(x[3].scale(gm[3]));
    let qt = q.minus(e3.scale(q.dot(e3)));
    let mut e_hg = half * e.k_m * qt.norm_squared();

    // rates: gradient sums of v and w in global axes, then their local components
    let (v, w) = (&e.v, &e.w);
    let dv13 = v[2].minus(v[0]);
    let dv24 = v[3].minus(v[1]);
    let dw13 = w[2].minus(w[0]);
    let dw24 = w[3].minus(w[1]);
    let vbx = dv13.scale(bx[0]).plus(dv24.scale(bx[1])); // sum_I bx_I v_I
    let vby = dv13.scale(by[0]).plus(dv24.scale(by[1]));
    let wbx = dw13.scale(bx[0]).plus(dw24.scale(bx[1]));
    let wby = dw13.scale(by[0]).plus(dw24.scale(by[1]));
    let wsum = w[0].plus(w[1]).plus(w[2]).plus(w[3]);
    let vg = v[0]
        .scale(gm[0])
        .plus(v[1].scale(gm[1]))
        .plus(v[2].scale(gm[2]))
        .plus(v[3].scale(gm[3]));
    let wg = w[0]
        .scale(gm[0])
        .plus(w[1].scale(gm[1]))
        .plus(w[2].scale(gm[2]))
        .plus(w[3].scale(gm[3]));
    let (wbx_x, wbx_y) = (wbx.dot(e1), wbx.dot(e2));
    let (wby_x, wby_y) = (wby.dot(e1), wby.dot(e2));
    let kr = [wbx_y, -wby_x, wby_y - wbx_x];
    let wm = [
        wsum.dot(e1) * quarter,
        wsum.dot(e2) * quarter,
        wsum.dot(e3) * quarter,
    ];
    let gr = [vbx.dot(e3) + wm[1], vby.dot(e3) - wm[0]];
    let spin = vbx.dot(e2) - vby.dot(e1);
    let drill_rate = wm[2] - half * spin;

    // rate-form plate resultants
    let (e_pl, mm, qq, (md, qd)) = plate_update(k, area, kr, gr, drill_rate, h, st);

    // rate-form hourglass resultants (w and rotations)
    hg.w += h * e.k_w * vg.dot(e3);
    hg.th[0] += h * e.k_th * wg.dot(e1);
    hg.th[1] += h * e.k_th * wg.dot(e2);
    let tiny = S::splat(f64::MIN_POSITIVE);
    e_hg += hg.w * hg.w * (half / e.k_w.max(tiny))
        + (hg.th[0] * hg.th[0] + hg.th[1] * hg.th[1]) * (half / e.k_th.max(tiny));

    // nodal forces: f_I = c_I + gamma_I G, with c_1 = -c_3, c_2 = -c_4
    let td = area * st.drill;
    let td_half = half * td;
    let gg = qt.scale(e.k_m).plus(e3.scale(hg.w));
    let bb = e3.scale(area * qq[0]).minus(e2.scale(td_half));
    let cc = e3.scale(area * qq[1]).plus(e1.scale(td_half));
    let [c3, c4] = corner_terms(e, [p1, p2, bb, cc], &bx, &by);
    // nodal moments: m_I = k + u_I + gamma_I H, with u_1 = -u_3, u_2 = -u_4
    let mb = e2.scale(area * mm[0]).minus(e1.scale(area * mm[2]));
    let mc = e2.scale(area * mm[2]).minus(e1.scale(area * mm[1]));
    let hh = e1.scale(hg.th[0]).plus(e2.scale(hg.th[1]));
    let aq = area * quarter;
    let kk = e2
        .scale(aq * qq[0])
        .minus(e1.scale(aq * qq[1]))
        .plus(e3.scale(td * quarter));
    let [u3, u4] = moment_terms(mb, mc, &bx, &by);
    let fs = [
        gg.scale(gm[0]).minus(c3),
        gg.scale(gm[1]).minus(c4),
        c3.plus(gg.scale(gm[2])),
        c4.plus(gg.scale(gm[3])),
    ];
    let ms = [kk.minus(u3), kk.minus(u4), kk.plus(u3), kk.plus(u4)];
    for i in 0..4 {
        let (f, m) = (fs[i], ms[i].plus(hh.scale(gm[i])));
        out[i] = [f.x, f.y, f.z, m.x, m.y, m.z];
    }
    if KELVIN && k.alpha > 0.0 {
        // the same combinations of the Kelvin resultants alone (drilling and hourglass
        // are not damped: no tau, no gamma terms)
        let p1 = f1.scale(sd[0]).plus(f2.scale(sd[2])).scale(e.area0);
        let p2 = f1.scale(sd[2]).plus(f2.scale(sd[1])).scale(e.area0);
        let bb = e3.scale(area * qd[0]);
        let cc = e3.scale(area * qd[1]);
        let [c3, c4] = corner_terms(e, [p1, p2, bb, cc], &bx, &by);
        let mb = e2.scale(area * md[0]).minus(e1.scale(area * md[2]));
        let mc = e2.scale(area * md[2]).minus(e1.scale(area * md[1]));
        let kk = e2.scale(aq * qd[0]).minus(e1.scale(aq * qd[1]));
        let [u3, u4] = moment_terms(mb, mc, &bx, &by);
        let z3 = V3::zero();
        let fs = [z3.minus(c3), z3.minus(c4), c3, c4];
        let ms = [kk.minus(u3), kk.minus(u4), kk.plus(u3), kk.plus(u4)];
        for i in 0..4 {
            let (f, m) = (fs[i], ms[i]);
            out_d[i] = [f.x, f.y, f.z, m.x, m.y, m.z];
        }
    }

    let diag = d13.norm_squared().max(d24.norm_squared()).sqrt();
    (
        KernelOut {
            internal: e_mem + e_pl,
            length: area / diag,
            ratio: area / e.area0,
        },
        QuadExtra {
            hourglass: e_hg,
            corners,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;

    #[test]
    fn reference_gradients_are_exactly_antisymmetric_across_the_diagonals() {
        // what lets QuadElem keep the gradients of nodes 3 and 4 only
        let x = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.3, 0.1, 0.01),
            Vec3::new(1.1, 0.9, -0.02),
            Vec3::new(-0.2, 0.7, 0.01),
        ];
        let (fr, c) = Frame::quad(&x);
        let xl = x.map(|p| (p - c).dot(&fr.e1));
        let yl = x.map(|p| (p - c).dot(&fr.e2));
        let (bx0, by0, _) = quad_gradients(xl, yl);
        for i in 0..2 {
            assert_eq!(bx0[i].to_bits(), (-bx0[i + 2]).to_bits());
            assert_eq!(by0[i].to_bits(), (-by0[i + 2]).to_bits());
        }
        let q = QuadElem::new([0, 1, 2, 3], &x);
        assert_eq!(q.bx0_all().map(f64::to_bits), bx0.map(f64::to_bits));
        assert_eq!(q.by0_all().map(f64::to_bits), by0.map(f64::to_bits));
    }

    #[test]
    fn derived_hourglass_data_have_the_bits_of_the_direct_formulas() {
        // QuadElem stores h.X, h.Y and bb in place of gamma and the three stiffnesses:
        // what it derives each cycle must be what the formulas give from the full
        // gradients (the state hashes depend on it)
        let sec = Section::new(Material::new(7800.0, 200e9, 0.3, 0.0).expect("valid"), 0.01);
        let stab = Stabilization::default();
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..1000 {
            let mut x = [
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ];
            for p in &mut x {
                *p = 0.37 * (*p + 0.3 * Vec3::new(next(), next(), 0.05 * next()));
            }
            let q = QuadElem::new([0, 1, 2, 3], &x);
            let (bx0, by0) = (q.bx0_all(), q.by0_all());
            let mut gamma = [0.0; 4];
            for (i, g) in gamma.iter_mut().enumerate() {
                *g = 0.25 * (HG[i] - q.hx * bx0[i] - q.hy * by0[i]);
            }
            assert_eq!(q.gamma().map(f64::to_bits), gamma.map(f64::to_bits));
            let bb = q.bb;
            let k = [
                stab.hourglass_membrane * sec.membrane * q.area0 * bb,
                stab.hourglass_w * sec.bending * q.area0 * bb * bb,
                stab.hourglass_rotation * sec.bending * q.area0 * bb,
            ];
            assert_eq!(
                q.stiffness(&sec, &stab).map(f64::to_bits),
                k.map(f64::to_bits)
            );
        }
    }
}
