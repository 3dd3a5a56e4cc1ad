//! A spherical shell dropped onto a fixed plate (the paper's first benchmark, small):
//! R = 0.1 m, t = 1 mm steel icosphere (level 4, 5120 triangles) at 2 m/s onto a
//! 0.3 m plate of 20 x 20 quads held fixed.

mod contact_util;

use contact_util::*;
use crash_core::contact::ContactConfig;
use crash_core::{Run, RunConfig, Vec3};

#[test]
fn sphere_dropped_on_fixed_plate_rebounds_with_small_penetration() {
    let (r, t, tp) = (0.1, 0.001, 0.002);
    let gap0 = 2e-4;
    let z0 = r + 0.5 * (t + tp) + gap0;
    let v0 = 2.0;
    let s = sphere(
        0,
        r,
        t,
        4,
        Vec3::new(0.0, 0.0, z0),
        Vec3::new(0.0, 0.0, -v0),
    );
    let p = fixed_plate(1, 0.3, 20, tp, 0.0);
    let cfg = ContactConfig {
        margin: 1e-3,
        ..Default::default()
    };
    let mut run = Run::new(
        group(vec![s, p], cfg),
        RunConfig {
            end_time: 2.5e-3,
            ..Default::default()
        },
    )
    .expect("start");
    let mut max_ratio: f64 = 0.0;
    let mut active = 0;
    let mut lowest = f64::INFINITY;
    run.run(|r| {
        for st in r.group.contact_stats() {
            max_ratio = max_ratio.max(st.max_penetration_ratio);
            active = active.max(st.active_nodes);
        }
        lowest = lowest.min(
            r.group.bodies[0]
                .state
                .x
                .iter()
                .map(|p| p.z)
                .fold(f64::INFINITY, f64::min),
        );
    })
    .expect("run");
    let vz = com_velocity(&run.group.bodies[0]).z;
    let zmin = run.group.bodies[0]
        .state
        .x
        .iter()
        .map(|p| p.z)
        .fold(f64::INFINITY, f64::min);
    println!(
        "rebound vz {vz:.4} m/s (restitution {:.3}), most active nodes {active}, max penetration / t {max_ratio:.4}, lowest node z {lowest:.3e} m (contact surface at {:.3e}), final {zmin:.3e}, balance max error {:.2e}, tree builds {}",
        vz / v0,
        0.5 * (t + tp),
        run.ledger.max_error(),
        run.group.contact_state.tree_builds()
    );
    assert!(active > 0, "contact happened");
    assert!(vz > 0.5 * v0, "it rebounds");
    assert!(max_ratio < 0.10, "penetration {max_ratio} of the thickness");
    // no node ever reaches the plate's mid-surface, and at the end all are clear of it
    assert!(lowest > 0.0);
    assert!(zmin > 0.5 * (t + tp));
    assert!(run.ledger.max_error() < 0.02);
}
