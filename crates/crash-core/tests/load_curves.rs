//! Load curves and support reactions against exact discrete results: a nodal force from
//! a piecewise-linear curve gives the curve's integral as impulse; a prescribed velocity
//! curve moves a node by the curve's integral; the reactions close the momentum balance
//! of every step.

mod common;

use common::*;
use crash_core::body::dof;
use crash_core::shapes::ElementKind;
use crash_core::{Clock, Group, NodalLoad, TimeCurve, Vec3, VelocityProgram, NO_CURVE};

/// A power of two: step times n h are exact, so curve points at multiples of H fall on
/// step boundaries bit for bit.
const H: f64 = 1.0 / 1_048_576.0;

fn plate() -> crash_core::Body {
    corner_plate(1.0, 1.0, 4, 4, ElementKind::Quad, steel(), 0.01)
}

/// Run `steps` steps of length H; `each` sees the group after every step.
fn steps(g: &mut Group, n: usize, mut each: impl FnMut(&Group, &Clock, &[crash_core::BodyReport])) {
    g.start().expect("start");
    let mut clock = Clock::default();
    for _ in 0..n {
        let r = g.advance(&clock, H).expect("step");
        clock = clock.after(H);
        each(g, &clock, &r);
    }
}

fn triangle(peak: f64) -> TimeCurve {
    TimeCurve {
        points: vec![(0.0, 0.0), (10.0 * H, peak), (30.0 * H, 0.0)],
    }
}

#[test]
fn nodal_force_curve_impulse_equals_curve_integral() {
    let mut b = plate();
    let c = b.add_curve(triangle(1.0)).expect("valid");
    let nn = b.node_count();
    let f = Vec3::new(0.3, -0.2, 1.0) * 50.0;
    for n in 0..nn {
        b.add_load(NodalLoad {
            node: n as u32,
            force: f,
            moment: Vec3::zeros(),
            t0: 0.0,
            t1: 0.0,
            curve: c,
        });
    }
    let mut g = Group::new(vec![b], Vec3::zeros());
    // the curve is back to zero at 30 H: after 40 steps the momentum is the impulse,
    // sum of hbar_n F(t_n) = trapezoid rule = exact integral of a piecewise-linear
    // curve with points on step boundaries: F * (30 H) / 2 per node
    steps(&mut g, 40, |_, _, _| {});
    let p = g.bodies[0].linear_momentum();
    let expected = f * (nn as f64) * (15.0 * H);
    let err = (p - expected).norm() / expected.norm();
    // tolerance: round-off of the sums (internal forces of a free body add to zero)
    assert!(
        err < 1e-12,
        "momentum {p:?}, impulse {expected:?}, rel {err:e}"
    );
}

#[test]
fn prescribed_velocity_curve_moves_by_its_integral() {
    for (name, curve, tol) in [
        // points on step boundaries: the midpoint sum is exact on every linear piece;
        // left is the round-off of adding 40 increments of ~1e-6 m to coordinates of
        // ~1 m (40 eps / 3e-5 ~ 3e-10)
        ("aligned", triangle(2.0), 3e-10),
        // a kink inside a step: the midpoint rule errs by at most h^2 |slope jump| / 8
        // per kink: 2 / (10 H) + 2 / (20 H) over 3 kinks, relative to the integral
        (
            "kinks inside steps",
            TimeCurve {
                points: vec![(0.0, 0.0), (10.3 * H, 2.0), (30.6 * H, 0.0)],
            },
            3.0 * (0.2 + 0.1) * H * H / 8.0 / H / (30.6 * H),
        ),
    ] {
        let mut b = plate();
        let c = b.add_curve(curve.clone()).expect("valid");
        let dir = Vec3::new(0.0, 0.6, 0.8);
        b.prescribe(
            &[0, 7],
            VelocityProgram {
                displacement: false,
                velocity: dir,
                angular: Vec3::zeros(),
                ramp: 0.0,
                curve: c,
            },
        );
        let mut g = Group::new(vec![b], Vec3::zeros());
        steps(&mut g, 40, |_, _, _| {});
        let b = &g.bodies[0];
        // exact integral of the piecewise-linear curve to 40 H (zero after its end)
        let area: f64 = curve
            .points
            .windows(2)
            .map(|w| 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0))
            .sum();
        for n in [0, 7] {
            let u = b.state.x[n] - b.def.x0[n];
            let err = (u - dir * area).norm() / area;
            assert!(
                err <= tol,
                "{name}: node {n} moved {u:?}, integral {area}, rel {err:e} > {tol:e}"
            );
        }
    }
}

#[test]
fn support_reaction_closes_momentum_balance_each_step() {
    let mut b = plate();
    for n in nodes_at(&b, 0, 0.0, 1e-9) {
        b.fix(n, dof::ALL);
    }
    let f = Vec3::new(0.0, 0.0, 40.0);
    let loaded = nodes_at(&b, 0, 1.0, 1e-9);
    for &n in &loaded {
        b.add_load(NodalLoad {
            node: n as u32,
            force: f,
            moment: Vec3::zeros(),
            t0: 0.0,
            t1: 0.0,
            curve: NO_CURVE,
        });
    }
    let applied = f * loaded.len() as f64;
    let mut g = Group::new(vec![b], Vec3::zeros());
    g.reactions = true;
    g.start().expect("start");
    let mut clock = Clock::default();
    let mut p_prev = g.bodies[0].linear_momentum();
    let mut worst: f64 = 0.0;
    for _ in 0..200 {
        let hbar = 0.5 * (clock.last_dt + H);
        let r = g.advance(&clock, H).expect("step");
        clock = clock.after(H);
        let rf = r[0]
            .reaction
            .expect("a supported body reports its reaction")
            .force;
        let p = g.bodies[0].linear_momentum();
        // d(momentum)/dt = applied + reaction (the element forces add up to zero)
        let err = ((p - p_prev) / hbar - (applied + rf)).norm() / applied.norm();
        worst = worst.max(err);
        p_prev = p;
    }
    assert!(
        worst < 1e-9,
        "momentum balance off by {worst:e} of the load"
    );
}
