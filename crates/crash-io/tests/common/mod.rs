//! Shared test scene: a quad plate and a triangulated sphere, deformed for a few steps
//! so that stresses, velocities and displacements are all non-zero.
#![allow(dead_code)]

use crash_core::shapes::{icosphere, plate, ElementKind};
use crash_core::Clock;
use crash_core::{Body, Group, Material, Section, Stabilization, Vec3};
use std::path::PathBuf;

pub fn steel(t: f64) -> Section {
    Section::new(Material::steel(), t)
}

/// Plate (id 3, quads) flexing and a sphere (id 1, triangles) breathing, apart.
pub fn bodies() -> Vec<Body> {
    let pm = plate(0.4, 0.3, 8, 6, ElementKind::Quad);
    let mut p = Body::new(3, "plate", &pm, steel(0.002), Stabilization::default()).expect("plate");
    for (x, v) in p.state.x.iter().zip(p.state.v.iter_mut()) {
        *v = Vec3::new(0.0, 0.0, 4.0 * (x.x / 0.2).powi(2) - 2.0);
    }
    let mut sm = icosphere(0.05, 2);
    sm.transform(&nalgebra::Matrix3::identity(), Vec3::new(0.0, 0.0, 0.3));
    let mut s = Body::new(1, "ball", &sm, steel(0.001), Stabilization::default()).expect("ball");
    let c = Vec3::new(0.0, 0.0, 0.3);
    for (x, v) in s.state.x.iter().zip(s.state.v.iter_mut()) {
        *v = 3.0 * (x - c) / 0.05 + Vec3::new(1.0, 0.0, -5.0);
    }
    vec![p, s]
}

/// The group after `steps` steps at 0.9 x the stable time step, with its clock.
pub fn stepped_group(steps: usize) -> (Clock, Group) {
    let mut g = Group::new(bodies(), Vec3::new(0.0, 0.0, -9.81));
    let mut clock = Clock::default();
    let mut reports = g.start().expect("start");
    for _ in 0..steps {
        let h = 0.9
            * reports
                .iter()
                .map(|r| r.stable_dt)
                .fold(f64::INFINITY, f64::min);
        reports = g.advance(&clock, h).expect("step");
        clock = clock.after(h);
    }
    (clock, g)
}

/// A fresh, empty directory for one test.
pub fn test_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("crash-io")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("test dir");
    d
}
