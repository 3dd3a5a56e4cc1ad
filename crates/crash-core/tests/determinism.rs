//! Determinism: the final state is bit-identical for 1, 2 and 4 threads.

mod common;

use common::*;
use crash_core::hash::state_hash;
use crash_core::shapes::{plate, ElementKind};
use crash_core::{Body, Group, Material, Run, RunConfig, Section, Stabilization, Vec3};

fn scene() -> Vec<Body> {
    // several chunks per body, both element kinds, Kelvin damping on one of them
    let mut out = Vec::new();
    for (id, kind) in [(0u32, ElementKind::Tri), (1, ElementKind::Quad)] {
        let mat =
            Material::new(7800.0, 200e9, 0.3, if id == 0 { 1e-7 } else { 0.0 }).expect("valid");
        let m = plate(0.4, 0.3, 40, 30, kind);
        let mut b = Body::new(
            id,
            "p",
            &m,
            Section::new(mat, 0.002),
            Stabilization::default(),
        )
        .expect("valid");
        for i in 0..b.state.x.len() {
            let p = b.def.x0[i];
            b.state.v[i] = Vec3::new(0.3 * p.y, 0.0, 2.0 * (9.0 * p.x).sin() * (7.0 * p.y).cos());
        }
        out.push(b);
    }
    out
}

fn final_hash(threads: usize) -> u64 {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let mut run = Run::new(
            Group::new(scene(), Vec3::new(0.0, 0.0, -9.81)),
            RunConfig {
                end_time: f64::INFINITY,
                ..Default::default()
            },
        )
        .expect("start");
        for _ in 0..300 {
            run.step().expect("stable");
        }
        state_hash(&run.group.bodies)
    })
}

#[test]
fn final_state_is_bit_identical_for_1_2_and_4_threads() {
    let h1 = final_hash(1);
    let h2 = final_hash(2);
    let h4 = final_hash(4);
    println!("state hashes: 1 thread {h1:016x}, 2 threads {h2:016x}, 4 threads {h4:016x}");
    assert_eq!(h1, h2);
    assert_eq!(h1, h4);
    let _ = kinds();
}
