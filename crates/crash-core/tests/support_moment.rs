//! The supports' resultant moment about the origin (spcforc.csv `mox_Nm..`) against
//! statics: a cantilever clamped at x = a with a tip load F at x = a + L, relaxed to
//! rest by mass damping, has support reactions -F and a moment about the clamp
//! M_O - C x R of F L (and F (a + L) about the origin).

mod common;

use common::*;
use crash_core::body::dof;
use crash_core::shapes::{plate, ElementKind};
use crash_core::{Clock, Group, NodalLoad, Vec3, NO_CURVE};

#[test]
fn cantilever_support_moment_about_clamp_equals_tip_load_times_length() {
    let (a, l, w, t) = (2.0, 1.0, 0.1, 0.02);
    // the clamp off the origin, so that the moment of the clamp's forces about the
    // origin counts (a test on the rotational reaction moments alone would fail)
    let mut m = plate(l, w, 20, 2, ElementKind::Quad);
    m.transform(
        &nalgebra::Matrix3::identity(),
        Vec3::new(a + l / 2.0, w / 2.0, 0.0),
    );
    let mut b = body(&m, steel(), t);
    for n in nodes_at(&b, 0, a, 1e-9) {
        b.fix(n, dof::ALL);
    }
    let tip = nodes_at(&b, 0, a + l, 1e-9);
    let f = 100.0;
    for &n in &tip {
        b.add_load(NodalLoad {
            node: n as u32,
            force: Vec3::new(0.0, 0.0, f / tip.len() as f64),
            moment: Vec3::zeros(),
            t0: 0.0,
            t1: 0.0,
            curve: NO_CURVE,
        });
    }
    // about twice the first bending frequency (1.875^2 sqrt(EI / (rho A L^4)) = 105
    // rad/s): close to critical for the mode that carries the static answer
    b.def_mut().mass_damping = 200.0;
    let mut g = Group::new(vec![b], Vec3::zeros());
    g.reactions = true;
    let start = g.start().expect("start");
    let h = 0.8 * start[0].stable_dt;
    let mut clock = Clock::default();
    let mut last = None;
    // 0.15 s: the slowest mode decays by exp(-100 * 0.15) ~ 3e-7
    while clock.time < 0.15 {
        let r = g.advance(&clock, h).expect("step");
        clock = clock.after(h);
        last = r[0].reaction;
    }
    let r = last.expect("a clamped body reports its reaction");
    // about the clamp's point C = (a, 0, 0): M_C = M_O - C x R; its y component
    // balances the tip load's F L
    let c = Vec3::new(a, 0.0, 0.0);
    let (fz, my) = (r.force.z, (r.moment_origin - c.cross(&r.force)).y);
    let my_o = r.moment_origin.y;
    assert!(
        ((my_o - f * (a + l)) / (f * (a + l))).abs() < 0.01,
        "support moment about the origin {my_o} N m, expected F (a + L) = {} N m",
        f * (a + l)
    );
    assert!(
        ((fz + f) / f).abs() < 0.01,
        "reaction force {fz} N, expected {} N",
        -f
    );
    assert!(
        ((my - f * l) / (f * l)).abs() < 0.01,
        "support moment about the clamp {my} N m, expected F L = {} N m",
        f * l
    );
}
