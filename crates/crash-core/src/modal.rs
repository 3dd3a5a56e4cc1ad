//! Highest natural frequency of a body by power iteration on M^-1/2 K M^-1/2, with K
//! applied matrix-free through the element kernels (a small increment from the current
//! state). Used to verify that the element time-step estimate is conservative, and by
//! `crash check`.

use crate::body::Body;
use crate::element::{HourglassState, ShellState};
use crate::Vec3;

/// Apply the tangent stiffness of `body` (at its current configuration, stress-free
/// rate state) to the nodal vector u = (translations, rotations); returns K u.
fn stiffness_action(base: &Body, u: &[[f64; 6]], eps: f64) -> Vec<[f64; 6]> {
    let mut b = base.clone();
    b.def_mut().section.material.kelvin = 0.0;
    for s in &mut b.state.shell {
        *s = ShellState::default();
    }
    for s in &mut b.state.hourglass {
        *s = HourglassState::default();
    }
    for i in 0..b.state.x.len() {
        let t = Vec3::new(u[i][0], u[i][1], u[i][2]) * eps;
        b.state.x[i] = base.state.x[i] + t;
        b.state.v[i] = t;
        b.state.w[i] = Vec3::new(u[i][3], u[i][4], u[i][5]) * eps;
    }
    let mut base_f = base.clone();
    base_f.def_mut().section.material.kelvin = 0.0;
    for s in &mut base_f.state.shell {
        *s = ShellState::default();
    }
    for s in &mut base_f.state.hourglass {
        *s = HourglassState::default();
    }
    base_f.state.v.iter_mut().for_each(|v| *v = Vec3::zeros());
    base_f.state.w.iter_mut().for_each(|v| *v = Vec3::zeros());
    let ok = b.internal_forces(1.0, 0).is_ok() && base_f.internal_forces(1.0, 0).is_ok();
    // the slots, not node sums (`summed`): differences slot by slot
    b.settle();
    base_f.settle();
    let mut out = vec![[0.0; 6]; b.state.x.len()];
    if !ok {
        return out;
    }
    for (i, o) in out.iter_mut().enumerate() {
        for &sl in
            &b.def.gather_slot[b.def.gather_start[i] as usize..b.def.gather_start[i + 1] as usize]
        {
            for d in 0..6 {
                o[d] += (b.state.slots[sl as usize][d] - base_f.state.slots[sl as usize][d]) / eps;
            }
        }
    }
    out
}

/// Estimate omega_max [rad/s] of the free (unconstrained DOFs) body.
pub fn max_frequency(body: &Body, iterations: usize) -> f64 {
    let n = body.state.x.len();
    let scale = crate::mesh::bounds(&body.state.x);
    let eps = 1e-9 * (scale.1 - scale.0).norm().max(1e-12);
    let minv: Vec<[f64; 6]> = (0..n)
        .map(|i| {
            let (m, r) = (
                body.def.mass[i].sqrt().recip(),
                body.def.inertia[i].sqrt().recip(),
            );
            [m, m, m, r, r, r]
        })
        .collect();
    let free = |i: usize, d: usize| body.def.fixed[i] & (1 << d) == 0;
    // deterministic start vector with high-frequency content
    let mut z: Vec<[f64; 6]> = (0..n)
        .map(|i| {
            std::array::from_fn(|d| {
                if free(i, d) {
                    (((i * 7 + d * 13) % 17) as f64 - 8.0) / 8.0
                } else {
                    0.0
                }
            })
        })
        .collect();
    let mut lambda = 0.0;
    for _ in 0..iterations {
        let norm = z.iter().flatten().map(|a| a * a).sum::<f64>().sqrt();
        if norm == 0.0 {
            return 0.0;
        }
        let u: Vec<[f64; 6]> = (0..n)
            .map(|i| std::array::from_fn(|d| z[i][d] / norm * minv[i][d]))
            .collect();
        let ku = stiffness_action(body, &u, eps);
        let y: Vec<[f64; 6]> = (0..n)
            .map(|i| {
                std::array::from_fn(|d| {
                    if free(i, d) {
                        ku[i][d] * minv[i][d]
                    } else {
                        0.0
                    }
                })
            })
            .collect();
        lambda = (0..n)
            .map(|i| (0..6).map(|d| y[i][d] * z[i][d] / norm).sum::<f64>())
            .sum::<f64>();
        z = y;
    }
    lambda.max(0.0).sqrt()
}
