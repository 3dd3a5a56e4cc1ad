//! Low-speed bounce of a thin spherical shell (R/t = 100) on a rigid plane in the linear
//! (Reissner) regime: the contact lasts pi sqrt(m / k), k = 4 E t^2 / (R sqrt(3(1-nu^2))).
//! Mesh: icosphere level 4 (5120 triangles), 0.5 m/s (peak approach about 0.2 t).

mod contact_util;

use contact_util::*;
use crash_core::contact::ContactConfig;
use crash_core::{Run, RunConfig, Vec3};

#[test]
fn contact_duration_matches_reissner_spring() {
    let (r, t, tp) = (0.1, 0.001, 0.001);
    let gap0 = 2e-5;
    let v0 = 0.5;
    let s = sphere(
        0,
        r,
        t,
        4,
        Vec3::new(0.0, 0.0, r + 0.5 * (t + tp) + gap0),
        Vec3::new(0.0, 0.0, -v0),
    );
    let m = s.total_mass();
    let p = fixed_plate(1, 0.1, 10, tp, 0.0);
    let k = reissner_stiffness(r, t);
    let expected = std::f64::consts::PI * (m / k).sqrt();
    let cfg = ContactConfig {
        margin: 5e-4,
        ..Default::default()
    };
    let mut run = Run::new(
        group(vec![s, p], cfg),
        RunConfig {
            end_time: gap0 / v0 + 1.3 * expected,
            ..Default::default()
        },
    )
    .expect("start");
    let (mut first, mut last) = (None, 0.0);
    let mut peak: f64 = 0.0;
    run.run(|r| {
        if let Some(st) = r.group.contact_stats().first() {
            if st.active_nodes > 0 {
                first.get_or_insert(r.time());
                last = r.time();
                peak = peak.max(st.normal_force);
            }
        }
    })
    .expect("run");
    let first = first.expect("contact happened");
    let duration = last - first;
    let vz = com_velocity(&run.group.bodies[0]).z;
    println!(
        "mass {m:.4} kg, k {k:.4e} N/m: expected {expected:.4e} s, measured {duration:.4e} s (ratio {:.4}); peak force {peak:.1} N (spring: {:.1} N); rebound {vz:.4} m/s; dt {:.3e}",
        duration / expected,
        v0 * (k * m).sqrt(),
        run.dt0
    );
    assert!(
        vz > 0.0 && last < run.time(),
        "the shell left the plane before the end"
    );
    assert!((duration / expected - 1.0).abs() < 0.15);
}
