//! Membrane wave speed: a step in velocity travels along a laterally constrained strip
//! at c = sqrt(E / (rho (1 - nu^2))) (5308 m/s for steel).

mod common;

use common::*;
use crash_core::body::dof;
use crash_core::{Group, Run, RunConfig, Vec3, VelocityProgram};

/// Time at which the x-velocity of the nodes at `x` first exceeds half the imposed one
/// (linear interpolation between steps).
fn arrival(history: &[(f64, f64)], level: f64) -> Option<f64> {
    history
        .windows(2)
        .find(|w| w[0].1 < level && w[1].1 >= level)
        .map(|w| w[0].0 + (level - w[0].1) / (w[1].1 - w[0].1) * (w[1].0 - w[0].0))
}

#[test]
fn membrane_wave_speed_matches_plate_theory() {
    let mat = steel();
    let exact = mat.wave_speed();
    for kind in kinds() {
        let mut b = corner_plate(1.0, 0.02, 200, 4, kind, mat, 0.002);
        // lateral strain suppressed (plane strain in y) and pure membrane motion
        for i in 0..b.state.x.len() {
            b.fix(i, dof::Y | dof::Z | dof::ROTATIONS);
        }
        let end: Vec<usize> = nodes_at(&b, 0, 0.0, 1e-9);
        b.prescribe(
            &end,
            VelocityProgram {
                displacement: false,
                velocity: Vec3::new(1.0, 0.0, 0.0),
                angular: Vec3::zeros(),
                ramp: 0.0,
                curve: crash_core::NO_CURVE,
            },
        );
        let probes = [0.3, 0.7];
        let sets: Vec<Vec<usize>> = probes.iter().map(|&x| nodes_at(&b, 0, x, 1e-6)).collect();
        let mut hist = vec![Vec::new(); 2];
        let mut run = Run::new(
            Group::new(vec![b], Vec3::zeros()),
            RunConfig {
                end_time: 0.9 / exact,
                ..Default::default()
            },
        )
        .expect("start");
        run.run(|r| {
            let b = &r.group.bodies[0];
            for (h, set) in hist.iter_mut().zip(&sets) {
                let v = set.iter().map(|&i| b.state.v[i].x).sum::<f64>() / set.len() as f64;
                h.push((r.time() - 0.5 * r.clock.last_dt, v));
            }
        })
        .expect("run");
        let t1 = arrival(&hist[0], 0.5).expect("front reached x = 0.3");
        let t2 = arrival(&hist[1], 0.5).expect("front reached x = 0.7");
        let c = (probes[1] - probes[0]) / (t2 - t1);
        let err = (c - exact) / exact;
        println!(
            "{kind:?}: measured {c:.1} m/s, theory {exact:.1} m/s, error {:.2}%",
            100.0 * err
        );
        assert!(err.abs() < 0.02, "{kind:?}: {err}");
    }
}
