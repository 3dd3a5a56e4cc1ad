//! Thin cantilever strip: small tip load (linear, no shear locking) and the
//! large-rotation roll-up under an end moment M = 2 pi E I / L.

mod common;

use common::*;
use crash_core::body::dof;
use crash_core::shapes::ElementKind;
use crash_core::{Group, Material, NodalLoad, Run, RunConfig, Vec3};

const L: f64 = 1.0;
const B: f64 = 0.1;
const T: f64 = 0.01;

fn strip(kind: ElementKind, nx: usize, ny: usize) -> crash_core::Body {
    // nu = 0: a strip of any width bends like a beam, D b = E I exactly
    let mat = Material::new(7800.0, 200e9, 0.0, 0.0).expect("valid");
    let mut b = corner_plate(L, B, nx, ny, kind, mat, T);
    for n in nodes_at(&b, 0, 0.0, 1e-9) {
        b.fix(n, dof::ALL);
    }
    b
}

/// Split a total end load over the tip nodes like a uniform line load.
fn tip_loads(b: &mut crash_core::Body, force: Vec3, moment: Vec3, ramp: f64) {
    let mut tip = nodes_at(b, 0, L, 1e-9);
    tip.sort_by(|&i, &j| b.def.x0[i].y.total_cmp(&b.def.x0[j].y));
    let n = tip.len() - 1;
    for (k, &node) in tip.iter().enumerate() {
        let w = if k == 0 || k == n { 0.5 } else { 1.0 } / n as f64;
        b.add_load(NodalLoad {
            node: node as u32,
            force: force * w,
            moment: moment * w,
            t0: 0.0,
            t1: ramp,
            curve: crash_core::NO_CURVE,
        });
    }
}

fn run(b: crash_core::Body, end: f64) -> crash_core::Body {
    let mut run = Run::new(
        Group::new(vec![b], Vec3::zeros()),
        RunConfig {
            end_time: end,
            ..Default::default()
        },
    )
    .expect("start");
    run.run(|_| {}).expect("run");
    run.group.bodies.remove(0)
}

fn mean_tip(b: &crash_core::Body) -> Vec3 {
    let tip = nodes_at(b, 0, L, 1e-9);
    tip.iter()
        .map(|&i| b.state.x[i] - b.def.x0[i])
        .sum::<Vec3>()
        / tip.len() as f64
}

#[test]
fn cantilever_tip_deflection_matches_beam_theory_without_shear_locking() {
    let e = 200e9;
    let inertia = B * T.powi(3) / 12.0;
    let p = 1.0;
    let exact = p * L.powi(3) / (3.0 * e * inertia);
    // first bending mode 8.2 Hz: critical mass damping 2 omega_1
    let omega1 = 1.875f64.powi(2) * (e * inertia / (7800.0 * B * T)).sqrt() / (L * L);
    for kind in kinds() {
        let mut b = strip(kind, 40, 4);
        b.def_mut().mass_damping = 2.0 * omega1;
        tip_loads(&mut b, Vec3::new(0.0, 0.0, -p), Vec3::zeros(), 0.05);
        let b = run(b, 0.25);
        let w = -mean_tip(&b).z;
        let err = (w - exact) / exact;
        println!(
            "{kind:?}: tip deflection {w:.6e} m, beam theory {exact:.6e} m, error {:.3}%",
            100.0 * err
        );
        assert!(err.abs() < 0.02, "{kind:?}: error {err}");
    }
}

#[test]
fn cantilever_rolls_into_a_full_circle_under_end_moment() {
    let e = 200e9;
    let inertia = B * T.powi(3) / 12.0;
    let moment = 2.0 * std::f64::consts::PI * e * inertia / L;
    let omega1 = 1.875f64.powi(2) * (e * inertia / (7800.0 * B * T)).sqrt() / (L * L);
    for kind in kinds() {
        let mut b = strip(kind, 40, 2);
        b.def_mut().mass_damping = 2.0 * omega1;
        // moment about -y rolls the strip up towards +z
        tip_loads(&mut b, Vec3::zeros(), Vec3::new(0.0, -moment, 0.0), 0.6);
        let b = run(b, 1.0);
        let tip: Vec3 = {
            let t = nodes_at(&b, 0, L, 1e-9);
            t.iter().map(|&i| b.state.x[i]).sum::<Vec3>() / t.len() as f64
        };
        let root = Vec3::new(0.0, B / 2.0, 0.0);
        let gap = (tip - root).norm();
        println!(
            "{kind:?}: tip at {tip:?}, distance to the clamped end {gap:.4} m ({:.2}% of L)",
            100.0 * gap / L
        );
        assert!(gap < 0.05 * L, "{kind:?}: tip {gap} m from the root");
    }
}
