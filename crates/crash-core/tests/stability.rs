//! Stability of the explicit scheme: the element time-step estimate is below the true
//! limit 2 / omega_max; long runs at the solver's own dt stay bounded and conserve
//! energy; a run forced above the limit is stopped with a diagnostic.

mod common;

use common::*;
use crash_core::modal::max_frequency;
use crash_core::shapes::{plate, ElementKind};
use crash_core::{Fault, Group, Run, RunConfig, Vec3};

/// Free steel plate 0.2 x 0.1 m, t = 2 mm, slightly distorted so that no symmetry hides
/// a mode, with a transverse velocity pattern.
fn free_plate(kind: ElementKind, nx: usize, ny: usize) -> crash_core::Body {
    let mut m = plate(0.2, 0.1, nx, ny, kind);
    for (i, p) in m.nodes.iter_mut().enumerate() {
        let s = ((i * 7919) % 13) as f64 / 13.0 - 0.5;
        if p.x.abs() < 0.099 && p.y.abs() < 0.049 {
            p.x += 0.15 * s * 0.2 / nx as f64;
            p.y -= 0.1 * s * 0.1 / ny as f64;
        }
    }
    let mut b = body(&m, steel(), 0.002);
    for i in 0..b.state.x.len() {
        let p = b.def.x0[i];
        b.state.v[i] = Vec3::new(
            0.0,
            0.0,
            0.5 * (std::f64::consts::PI * p.x / 0.2).cos() * (p.y / 0.1),
        );
    }
    b
}

fn critical_dt(b: &crash_core::Body) -> f64 {
    let g = Group::new(vec![b.clone()], Vec3::zeros());
    let run = Run::new(
        g,
        RunConfig {
            end_time: 1.0,
            safety: 1.0,
            ..Default::default()
        },
    )
    .expect("start");
    run.next_dt
}

/// Meshes that stress the estimate: a distorted plate, a one-row strip, cells of aspect
/// 5, and a single cell (corner nodes held by one element).
fn estimate_cases(kind: ElementKind) -> Vec<(&'static str, crash_core::Body)> {
    let strip = |nx, ny, lx, ly| body(&plate(lx, ly, nx, ny, kind), steel(), 0.002);
    vec![
        ("distorted 8x4 plate", free_plate(kind, 8, 4)),
        ("10x1 strip", strip(10, 1, 1.0, 0.1)),
        ("8x4 cells of aspect 5", strip(8, 4, 1.0, 0.05)),
        ("single cell", strip(1, 1, 0.1, 0.1)),
    ]
}

#[test]
fn element_time_step_estimate_is_below_the_true_stability_limit() {
    for kind in kinds() {
        for (name, b) in estimate_cases(kind) {
            let omega = max_frequency(&b, 3000);
            let dt_est = critical_dt(&b);
            let ratio = omega * dt_est / 2.0;
            println!("{kind:?} {name}: omega_max = {omega:.4e} rad/s, dt_estimate = {dt_est:.4e} s, dt_estimate / (2/omega_max) = {ratio:.3}");
            assert!(
                ratio <= 1.0,
                "{kind:?} {name}: estimate {dt_est} exceeds the limit {}",
                2.0 / omega
            );
            assert!(
                ratio > 0.4,
                "{kind:?} {name}: estimate needlessly conservative ({ratio})"
            );
        }
    }
}

#[test]
fn undamped_free_vibration_keeps_energy_balance_for_20000_steps() {
    for kind in kinds() {
        let b = free_plate(kind, 20, 10);
        let mut run = Run::new(
            Group::new(vec![b], Vec3::zeros()),
            RunConfig {
                end_time: f64::INFINITY,
                ..Default::default()
            },
        )
        .expect("start");
        for _ in 0..20_000 {
            run.step().expect("stable");
        }
        let err = run.ledger.max_error();
        println!(
            "{kind:?}: max energy-balance error over 20000 steps {:.3e}",
            err
        );
        assert!(err < 0.005, "{kind:?}: {err}");
    }
}

#[test]
fn hundred_thousand_steps_at_own_time_step_stay_bounded() {
    for kind in kinds() {
        let b = free_plate(kind, 8, 4);
        let e0 = b.kinetic_energy_now();
        let mut run = Run::new(
            Group::new(vec![b], Vec3::zeros()),
            RunConfig {
                end_time: f64::INFINITY,
                ..Default::default()
            },
        )
        .expect("start");
        for _ in 0..100_000 {
            run.step().expect("stable");
        }
        let e = run.energy;
        let mech = e.kinetic + e.internal + e.hourglass;
        println!(
            "{kind:?}: after 100000 steps E_mech / E_0 = {:.6}, max balance error {:.3e}",
            mech / e0,
            run.ledger.max_error()
        );
        assert!((mech / e0 - 1.0).abs() < 0.01);
        assert!(run.ledger.max_error() < 0.01);
    }
}

#[test]
fn time_step_above_the_critical_one_is_stopped_with_a_diagnostic() {
    for kind in kinds() {
        let b = free_plate(kind, 8, 4);
        let omega = max_frequency(&b, 3000);
        let dt = 1.2 * 2.0 / omega;
        let mut run = Run::new(
            Group::new(vec![b], Vec3::zeros()),
            RunConfig {
                end_time: 1.0,
                fixed_dt: Some(dt),
                ..Default::default()
            },
        )
        .expect("start");
        let mut steps = 0;
        let res = loop {
            steps += 1;
            if let Err(f) = run.step() {
                break Some(f);
            }
            if steps > 5000 {
                break None;
            }
        };
        let fault = res.expect("an unstable run must be stopped");
        let msg = fault.to_string();
        println!("{kind:?}: stopped after {steps} steps: {msg}");
        assert!(matches!(
            fault,
            Fault::EnergyRunaway { .. }
                | Fault::NonFinite { .. }
                | Fault::Collapsed { .. }
                | Fault::Inverted { .. }
        ));
        assert!(msg.contains("step") && msg.contains("body"), "{msg}");
        // nothing non-finite was written into the state
        assert!(run.group.bodies[0]
            .state
            .x
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite())));
    }
}
