//! Reissner's point-load stiffness of a thin spherical shell, loaded through contact:
//! a clamped cap (R/t = 100) is pressed slowly by a rigid plane moving up.

mod contact_util;

use contact_util::*;
use crash_core::contact::ContactConfig;
use crash_core::{Run, RunConfig, Vec3, VelocityProgram};

#[test]
fn force_approach_slope_matches_reissner_stiffness() {
    let (r, t, tp) = (0.1, 0.001, 0.001);
    let (mesh, rim) = cap(r, 6, 25f64.to_radians());
    let mut c = shell(0, &mesh, t);
    for &n in &rim {
        c.fix(n, crash_core::dof::ALL);
    }
    c.def_mut().mass_damping = 5000.0;
    let pole = (0..c.state.x.len())
        .min_by(|&a, &b| c.state.x[a].z.total_cmp(&c.state.x[b].z))
        .expect("nodes");
    let gap0 = 5e-5;
    let vp = 0.2;
    let mut p = fixed_plate(1, 0.04, 8, tp, -r - 0.5 * (t + tp) - gap0);
    let all: Vec<usize> = (0..p.state.x.len()).collect();
    p.prescribe(
        &all,
        VelocityProgram {
            displacement: false,
            velocity: Vec3::new(0.0, 0.0, vp),
            angular: Vec3::zeros(),
            ramp: 2e-4,
            curve: crash_core::NO_CURVE,
        },
    );
    let cfg = ContactConfig {
        margin: 1e-3,
        ..Default::default()
    };
    let end = 2e-4 / 2.0 + (gap0 + 0.52 * t) / vp;
    let mut run = Run::new(
        group(vec![c, p], cfg),
        RunConfig {
            end_time: end,
            ..Default::default()
        },
    )
    .expect("start");
    println!(
        "elements {}, dt {:.3e}, steps ~{:.0}",
        run.group.bodies[0].element_count(),
        run.dt0,
        end / run.dt0
    );
    let z0 = run.group.bodies[0].state.x[pole].z;
    let mut curve = Vec::new();
    run.run(|r| {
        let w = r.group.bodies[0].state.x[pole].z - z0;
        let f = r
            .group
            .contact_stats()
            .first()
            .map_or(0.0, |s| s.normal_force);
        curve.push((w, f));
    })
    .expect("run");
    let k = reissner_stiffness(r, t);
    for (i, (w, f)) in curve.iter().enumerate() {
        if i % 1500 == 0 {
            println!("w/t {:.4} F {:.1} N  F/(k w) {:.3}", w / t, f, f / (k * w));
        }
    }
    // chord slope through the origin over the whole range w <= t/2 (least squares),
    // and the initial tangent (w <= t/4)
    let below: Vec<(f64, f64)> = curve
        .iter()
        .copied()
        .filter(|(w, _)| *w > 0.0 && *w <= 0.5 * t)
        .collect();
    let chord = below.iter().map(|(w, f)| w * f).sum::<f64>()
        / below.iter().map(|(w, _)| w * w).sum::<f64>();
    let early: Vec<(f64, f64)> = below
        .iter()
        .copied()
        .filter(|(w, _)| *w <= 0.25 * t)
        .collect();
    let tangent = slope(&early);
    let reach = below.iter().map(|p| p.0).fold(0.0, f64::max);
    println!(
        "Reissner k {k:.4e} N/m; chord slope (w <= t/2) {chord:.4e} (ratio {:.4}); initial slope (w <= t/4) {tangent:.4e} (ratio {:.4}); {} samples up to w/t = {:.3}",
        chord / k,
        tangent / k,
        below.len(),
        reach / t
    );
    assert!(reach > 0.45 * t, "the load must reach the range");
    assert!((chord / k - 1.0).abs() < 0.10);
    assert!((tangent / k - 1.0).abs() < 0.10);
}
