//! Two spherical shells colliding: head-on (momentum, velocity exchange, energy) and
//! oblique (linear and angular momentum). Steel, R = 0.1 m, t = 1 mm.

mod contact_util;

use contact_util::*;
use crash_core::contact::{ContactConfig, ContactPass};
use crash_core::{Run, RunConfig, Vec3};

#[test]
fn head_on_spheres_conserve_momentum_and_exchange_velocities() {
    let (r, t) = (0.1, 0.001);
    let v0 = 1.0;
    let (a, b) = head_on_pair(r, t, 4, 1e-4, v0);
    let cfg = ContactConfig {
        margin: 1e-3,
        ..Default::default()
    };
    let mut run = Run::new(
        group(vec![a, b], cfg),
        RunConfig {
            end_time: 1.6e-3,
            ..Default::default()
        },
    )
    .expect("start");
    let p_scale = run.group.bodies[0].total_mass() * v0;
    let mut worst: f64 = 0.0;
    let mut touched = false;
    let mut last_active = 0.0;
    run.run(|r| {
        worst = worst.max(total_momentum(&r.group).norm() / p_scale);
        if r.group.contact_stats().iter().any(|s| s.active_nodes > 0) {
            touched = true;
            last_active = r.time();
        }
    })
    .expect("run");
    let va = com_velocity(&run.group.bodies[0]);
    let vb = com_velocity(&run.group.bodies[1]);
    println!(
        "after: va {:.4} vb {:.4} (before {v0}, {}); separated at {last_active:.3e} s of {:.3e}; momentum drift {worst:.2e} of m v; balance max error {:.2e}",
        va.x,
        vb.x,
        -v0,
        run.time(),
        run.ledger.max_error()
    );
    assert!(
        touched && last_active < run.time(),
        "they touched and separated"
    );
    assert!(worst < 1e-12);
    assert!((va.x + v0).abs() < 0.05 * v0 && (vb.x - v0).abs() < 0.05 * v0);
    assert!(run.ledger.max_error() < 0.01);
}

#[test]
fn oblique_impact_conserves_linear_and_angular_momentum() {
    oblique_impact(ContactPass::Nodes);
}

/// The segment pass: its node forces are the exact gradient of a potential invariant
/// under rigid motions, so they sum to zero and have no moment.
#[test]
fn oblique_impact_conserves_linear_and_angular_momentum_with_the_segment_pass() {
    oblique_impact(ContactPass::Segments);
}

fn oblique_impact(pass: ContactPass) {
    let (r, t): (f64, f64) = (0.1, 0.002);
    let v0 = 2.0;
    // centres half a radius apart sideways, surfaces 0.1 mm apart; spin on one of them
    let x0 = 0.5 * ((2.0 * r + t + 1e-4).powi(2) - (0.5 * r).powi(2)).sqrt();
    let a = sphere(
        0,
        r,
        t,
        3,
        Vec3::new(-x0, -0.5 * r, 0.03),
        Vec3::new(v0, 0.0, 0.0),
    );
    let mut b = sphere(
        1,
        r,
        t,
        3,
        Vec3::new(x0, 0.0, 0.03),
        Vec3::new(-v0, 0.5, 0.0),
    );
    let cb = b.centre_of_mass();
    let vb = com_velocity(&b);
    b.set_rigid_velocity(vb, Vec3::new(0.0, 20.0, 5.0), cb);
    let cfg = ContactConfig {
        margin: 1e-3,
        pass,
        ..Default::default()
    };
    let mut run = Run::new(
        group(vec![a, b], cfg),
        RunConfig {
            end_time: 2e-3,
            ..Default::default()
        },
    )
    .expect("start");
    let p0 = total_momentum(&run.group);
    let l0 = total_angular_momentum(&run.group);
    let (mut dp, mut dl): (f64, f64) = (0.0, 0.0);
    let mut impulse: f64 = 0.0;
    let (mut window, mut window_end) = (None, 0.0);
    run.run(|r| {
        dp = dp.max(
            (total_momentum(&r.group) - p0).norm()
                / p0.norm().max(r.group.bodies[0].total_mass() * v0),
        );
        dl = dl.max((total_angular_momentum(&r.group) - l0).norm() / l0.norm());
        for s in r.group.contact_stats() {
            impulse = impulse.max(s.normal_force);
            if s.active_nodes > 0 {
                window.get_or_insert(r.time());
                window_end = r.time();
            }
        }
    })
    .expect("run");
    let deflected = com_velocity(&run.group.bodies[0]);
    println!(
        "|p0| {:.4e}, |L0| {:.4e}; max relative drift: momentum {dp:.2e}, angular momentum {dl:.2e}; peak contact force {impulse:.1} N, contact {window:?}..{window_end:.3e} s; sphere 0 leaves with {deflected:?}",
        p0.norm(),
        l0.norm()
    );
    assert!(
        impulse > 0.0 && window_end < run.time(),
        "they collided and separated"
    );
    assert!(
        deflected.y.abs() > 0.05 * v0,
        "the impact was oblique (sideways deflection)"
    );
    assert!(dp < 1e-10);
    assert!(dl < 1e-10);
}
