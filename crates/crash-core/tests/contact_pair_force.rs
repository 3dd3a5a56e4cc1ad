//! The pair force contact reports (rcforc.csv): in a head-on impact of two spherical
//! shells the force on one body is equal and opposite to the force on the other, and
//! its time integral is each body's momentum change.

mod contact_util;

use contact_util::*;
use crash_core::contact::ContactConfig;
use crash_core::{Clock, Vec3};

#[test]
fn pair_force_is_equal_and_opposite_and_its_impulse_is_the_momentum_change() {
    let (r, t, v0) = (0.05, 0.001, 2.0);
    let (a, b) = head_on_pair(r, t, 3, 2e-4, v0);
    let cfg = ContactConfig {
        margin: 1e-3,
        ..Default::default()
    };
    let mut g = group(vec![a, b], cfg);
    let p0 = [g.bodies[0].linear_momentum(), g.bodies[1].linear_momentum()];
    let mut reports = g.start().expect("start");
    // the pair force of a pass acts over the next step's hbar
    let mut force = g
        .contact_stats()
        .first()
        .map_or(Vec3::zeros(), |s| s.force_on_a);
    let mut impulse = Vec3::zeros();
    let mut clock = Clock::default();
    let mut peak: f64 = 0.0;
    while clock.time < 1.0e-3 {
        let h = 0.9
            * reports
                .iter()
                .map(|r| r.stable_dt)
                .fold(f64::INFINITY, f64::min);
        impulse += force * (0.5 * (clock.last_dt + h));
        reports = g.advance(&clock, h).expect("step");
        clock = clock.after(h);
        let stats = g.contact_stats();
        force = stats.first().map_or(Vec3::zeros(), |s| s.force_on_a);
        peak = peak.max(force.norm());
    }
    assert!(peak > 0.0, "the shells never touched");
    let dpa = g.bodies[0].linear_momentum() - p0[0];
    let dpb = g.bodies[1].linear_momentum() - p0[1];
    let scale = impulse.norm();
    // the impact reverses most of m v0: the impulse is of order 2 m v0
    assert!(scale > g.bodies[0].total_mass() * v0, "impulse {impulse:?}");
    // tolerance: round-off of the force sums over the steps (1e-9 of the impulse)
    assert!(
        (dpa - impulse).norm() < 1e-9 * scale,
        "body a: {dpa:?} vs {impulse:?}"
    );
    assert!(
        (dpb + impulse).norm() < 1e-9 * scale,
        "body b: {dpb:?} vs {:?}",
        -impulse
    );
}
