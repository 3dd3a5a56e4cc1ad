//! A built scene runs in the core driver as it is: initial velocity, gravity, spin and
//! supports come out as the scene says.

use crash_core::{Group, Run, Vec3};
use std::path::PathBuf;

fn built(file: &str) -> crash_scene::Built {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(file);
    crash_scene::load(&p)
        .and_then(|s| s.build())
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn falling_sphere_keeps_its_velocity_plus_gravity_before_contact() {
    let b = built("sphere-on-plate-small.toml");
    let cfg = b.run_config();
    let mut run = Run::new(Group::new(b.bodies.clone(), b.gravity), cfg).expect("start");
    for _ in 0..20 {
        run.step().expect("step");
    }
    // 20 steps of ~0.95 us: the 0.5 mm gap is far from closed
    let t = run.time();
    assert!(t > 0.0 && t < 5.0e-5, "{t}");
    let sphere = &run.group.bodies[1];
    let v = sphere.linear_momentum() / sphere.total_mass();
    // half-step velocity v_{n-1/2}: -5 - g (t - h/2)
    let h = run.clock.last_dt;
    let expect = Vec3::new(0.0, 0.0, -5.0 - 9.81 * (t - 0.5 * h));
    assert!((v - expect).norm() < 1e-9, "{v} vs {expect}");
    // clamped edges did not move
    let plate = &run.group.bodies[0];
    for i in 0..plate.node_count() {
        if plate.def.fixed[i] != 0 {
            assert_eq!(plate.state.x[i], plate.def.x0[i]);
        }
    }
}

#[test]
fn spinning_free_plate_starts_as_a_rigid_body() {
    let b = built("free-plate-spin.toml");
    let mut run = Run::new(Group::new(b.bodies.clone(), b.gravity), b.run_config()).expect("start");
    let p0 = run.group.bodies[0].linear_momentum();
    let e0 = run.group.bodies[0].kinetic_energy_now();
    for _ in 0..100 {
        run.step().expect("step");
    }
    let body = &run.group.bodies[0];
    assert!((body.linear_momentum() - p0).norm() < 1e-9 * p0.norm());
    // node rotation rates equal to the body's spin excite no bending or drilling: only
    // the centrifugal stretch, strain ~ rho w^2 r^2 / E ~ 5e-6, stores energy (observed
    // 4e-6 of the kinetic energy; with the node rotation rates left at zero it is 6e-4)
    assert!(
        body.state.energy.internal < 5e-5 * e0,
        "{} vs {e0}",
        body.state.energy.internal
    );
}
