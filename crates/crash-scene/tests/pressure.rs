//! `pressure` on a body: a free flat plate under pressure p gains momentum p A t
//! (analytic: the only force is p A along -n), and a curve scales it in time.

use crash_core::{Clock, Group, Vec3};

fn scene(pressure: &str) -> String {
    format!(
        r#"
name = "pressure"
end_time = 1.0e-3
gravity = [0.0, 0.0, 0.0]

[materials.steel]
density = 7800.0
young = 2.0e11
poisson = 0.3

[[bodies]]
name = "plate"
material = "steel"
thickness = 2.0e-3
plate = {{ size = [0.4, 0.2], cells = [8, 4] }}
{pressure}
"#
    )
}

/// Momentum after `n` steps of length h (a power of two: step times are exact).
fn momentum(text: &str, n: usize, h: f64) -> (Vec3, f64) {
    let built = crash_scene::parse(text, "scene.toml")
        .and_then(|s| s.build())
        .unwrap_or_else(|e| panic!("{e}"));
    let mut g = Group::new(built.bodies, Vec3::zeros());
    g.start().expect("start");
    let mut clock = Clock::default();
    for _ in 0..n {
        g.advance(&clock, h).expect("step");
        clock = clock.after(h);
    }
    let b = &g.bodies[0];
    (b.linear_momentum(), b.total_mass())
}

const H: f64 = 1.0 / 4_194_304.0;

#[test]
fn pressure_on_a_free_plate_gives_momentum_p_a_t() {
    let p = 2.5e3;
    let area = 0.4 * 0.2;
    let n = 100;
    let (mom, _) = momentum(&scene(&format!("pressure = [{{ value = {p} }}]")), n, H);
    // v_{n+1/2} = sum of hbar F: the momentum is F t at the half step after t_{n-1}
    let t = (n as f64 - 0.5) * H;
    // the plate lies in z = 0 with its normal +z: positive pressure pushes along -z
    let expected = Vec3::new(0.0, 0.0, -p * area * t);
    let err = (mom - expected).norm() / expected.norm();
    // tolerance: round-off of summing 45 nodes over 100 steps
    assert!(
        err < 1e-12,
        "momentum {mom:?}, p A t = {expected:?}, rel {err:e}"
    );
}

#[test]
fn pressure_curve_scales_the_impulse() {
    let p = 2.5e3;
    let area = 0.4 * 0.2;
    // a triangle over 60 steps, points on step boundaries: impulse p A 60 H / 2
    let text = scene(&format!(
        "pressure = [{{ value = {p}, curve = \"pulse\" }}]\n\n[curves.pulse]\npoints = [[0.0, 0.0], [{}, 1.0], [{}, 0.0]]\n",
        20.0 * H,
        60.0 * H
    ));
    let (mom, _) = momentum(&text, 80, H);
    let expected = Vec3::new(0.0, 0.0, -p * area * 30.0 * H);
    let err = (mom - expected).norm() / expected.norm();
    assert!(
        err < 1e-12,
        "momentum {mom:?}, impulse {expected:?}, rel {err:e}"
    );
}
