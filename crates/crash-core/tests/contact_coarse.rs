//! The segment pass on a coarse curved mesh: a level-1 icosphere (80 triangles, edges
//! about 0.6 R, its curved surface up to 1.3 c off its facets) thrown onto a fixed plate.
//! docs/theory-contact.md, "Segment pass", "Penetration on coarse meshes".

mod contact_util;

use contact_util::*;
use crash_core::contact::{ContactConfig, ContactPass, REFERENCE_SAFETY};
use crash_core::{Run, RunConfig, Vec3};
use std::f64::consts::PI;

/// The penalty law of the segment pass, kappa = s mu / dt_ref^2 per unit area (both
/// directions together), stores V = kappa pi R delta^3 / 3 in a smooth sphere of radius R
/// pressed delta into the contact surface. The contact can store at most the impact's
/// kinetic energy, so the deepest point stays within the Hertz depth
/// delta_H = (3 M v^2 / (2 pi kappa R))^(1/3) (the shell's own strain and vibration only
/// take energy away). Points missed by the search make the contact softer and deeper:
/// with the master's bulge beyond the search reach (c + 0.25 c), the plate's points
/// facing a ball facet's middle were dropped and this sphere sank 14 % beyond delta_H,
/// with 0.63 kappa pi R delta^2 at its deepest. At the deepest pass the contact force
/// stays near the smooth sphere's kappa pi R delta^2.
#[test]
fn coarse_sphere_penetration_stays_within_the_hertz_depth_of_the_penalty_law() {
    let (r, t, tp, v0) = (0.03, 5e-4, 2e-3, 5.0);
    let c = 0.5 * (t + tp);
    let z0 = r + c + 1e-4;
    let s = sphere(
        0,
        r,
        t,
        1,
        Vec3::new(0.0, 0.0, z0),
        Vec3::new(0.0, 0.0, -v0),
    );
    let mass = s.total_mass();
    let p = fixed_plate(1, 0.12, 24, tp, 0.0);
    let cfg = ContactConfig {
        pass: ContactPass::Segments,
        ..Default::default()
    };
    let scale = cfg.penalty_scale;
    // the lighter areal mass: the sphere's (its mesh's area is below 4 pi R^2; the
    // lumped mass is rho t times the facets' area)
    let mu = 7800.0 * t;
    let mut run = Run::new(
        group(vec![s, p], cfg),
        RunConfig {
            end_time: 6e-4,
            ..Default::default()
        },
    )
    .expect("start");
    // (depth, force, kappa) at the deepest pass
    let mut deepest = (0.0f64, 0.0, 0.0);
    run.run(|r| {
        let dt_ref = REFERENCE_SAFETY * r.reports[0].stable_dt.min(r.reports[1].stable_dt);
        let kappa = scale * mu / (dt_ref * dt_ref);
        for st in r.group.contact_stats() {
            if st.max_penetration > deepest.0 {
                deepest = (st.max_penetration, st.normal_force, kappa);
            }
        }
    })
    .expect("run");
    let (depth, force, kappa) = deepest;
    let hertz = (3.0 * mass * v0 * v0 / (2.0 * PI * kappa * r)).cbrt();
    let stiffness = force / (PI * r * depth * depth) / kappa;
    let vz = com_velocity(&run.group.bodies[0]).z;
    println!(
        "deepest {depth:.4e} m = {:.3} c = {:.3} t (Hertz depth {hertz:.4e} m = {:.3} c), force / (kappa pi R depth^2) {stiffness:.3}, rebound {:.3}, balance {:.2e}",
        depth / c,
        depth / t,
        hertz / c,
        vz / v0,
        run.ledger.max_error()
    );
    assert!(depth > 0.0 && vz > 0.0, "it hits and rebounds");
    assert!(
        depth < 1.05 * hertz,
        "depth {depth:e} beyond the Hertz depth {hertz:e} of the penalty law"
    );
    assert!(
        stiffness > 0.8,
        "contact stiffness {stiffness} of kappa pi R delta^2"
    );
    assert!(run.ledger.max_error() < 0.02);
}
