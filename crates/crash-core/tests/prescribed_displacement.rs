//! Prescribed displacement (LS-DYNA VAD = 2): nodes driven by a displacement curve
//! are at x0 + D d(t_n) at every step (the step's velocity is the curve's change over
//! it, so nothing drifts), and the energy balance closes with the supports' work.

mod common;

use common::*;
use crash_core::shapes::ElementKind;
use crash_core::{Group, Run, RunConfig, TimeCurve, Vec3, VelocityProgram, NO_CURVE};

/// A power of two: step times n H are exact.
const H: f64 = 1.0 / 1_048_576.0;

/// A linear ramp to 1 at 20 H, then a sine sampled as a table at steps of 3.3 H (its
/// points fall inside steps).
fn ramp_then_sine() -> TimeCurve {
    let mut points = vec![(0.0, 0.0)];
    let t1 = 20.0 * H;
    for k in 0..=32 {
        let phase = 2.0 * std::f64::consts::PI * k as f64 / 16.0;
        points.push((t1 + 3.3 * H * k as f64, 1.0 + 0.5 * phase.sin()));
    }
    TimeCurve { points }
}

fn run_with(program: VelocityProgram, curve: Option<TimeCurve>) -> (Run, Vec<usize>, Vec3) {
    let mut b = corner_plate(1.0, 1.0, 4, 4, ElementKind::Quad, steel(), 0.01);
    let mut p = program;
    if let Some(c) = curve {
        p.curve = b.add_curve(c).expect("valid curve");
    }
    let edge = nodes_at(&b, 0, 0.0, 1e-9);
    b.prescribe(&edge, p);
    let run = Run::new(
        Group::new(vec![b], Vec3::zeros()),
        RunConfig {
            end_time: 160.0 * H,
            fixed_dt: Some(H),
            ..Default::default()
        },
    )
    .expect("start");
    (run, edge, p.velocity)
}

#[test]
fn prescribed_displacement_puts_nodes_at_the_curve_every_step() {
    let curve = ramp_then_sine();
    let d = Vec3::new(0.0, 2e-5, 1e-4);
    let program = VelocityProgram {
        velocity: d,
        angular: Vec3::zeros(),
        ramp: 0.0,
        curve: NO_CURVE,
        displacement: true,
    };
    let (mut run, edge, d) = run_with(program, Some(curve.clone()));
    let mut worst: f64 = 0.0;
    let mut steps = 0;
    while run.time() < 160.0 * H * (1.0 - 1e-12) {
        run.step().expect("step");
        steps += 1;
        let b = &run.group.bodies[0];
        let want = d * curve.value(run.time());
        for &n in &edge {
            let u = b.state.x[n] - b.def.x0[n];
            // relative to the position's size: the round-off of adding the step
            // increments to the coordinates (x0 up to 1 m, d ~ 1e-4 m)
            let scale = b.def.x0[n].norm().max(want.norm());
            worst = worst.max((u - want).norm() / scale);
        }
    }
    assert_eq!(steps, 160);
    eprintln!("worst {worst:e}, balance {:e}", run.ledger.max_error());
    assert!(worst < 1e-12, "off the curve by {worst:e} of the position");
    // the supports' work is in the external column: the balance closes
    let balance = run.ledger.max_error();
    // measured 9.6e-9 (round-off of the work sums)
    assert!(balance < 1e-7, "energy balance error {balance:e}");
}

#[test]
fn prescribed_displacement_ramp_moves_linearly_then_holds() {
    // no curve: d(t) = D min(t / ramp, 1)
    let d = Vec3::new(0.0, 0.0, 5e-5);
    let program = VelocityProgram {
        velocity: d,
        angular: Vec3::zeros(),
        ramp: 40.0 * H,
        curve: NO_CURVE,
        displacement: true,
    };
    let (mut run, edge, _) = run_with(program, None);
    while run.time() < 160.0 * H * (1.0 - 1e-12) {
        run.step().expect("step");
        let b = &run.group.bodies[0];
        let want = d * (run.time() / (40.0 * H)).min(1.0);
        for &n in &edge {
            let u = b.state.x[n] - b.def.x0[n];
            let scale = b.def.x0[n].norm().max(want.norm());
            assert!(
                (u - want).norm() <= 1e-12 * scale,
                "t {}: node {n} moved {u:?}, want {want:?}",
                run.time()
            );
        }
    }
}
