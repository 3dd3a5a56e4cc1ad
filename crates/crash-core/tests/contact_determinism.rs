//! Determinism of contact: the same bits for 1, 2 and 4 threads, and for a colliding
//! pair whether or not an unrelated body shares its group.

mod contact_util;

use contact_util::*;
use crash_core::contact::{ContactConfig, ContactPass, ContactState};
use crash_core::hash::state_hash;
use crash_core::{Body, Run, RunConfig, Vec3};

/// Two spheres (level 3, 642 nodes each: two node chunks) in an oblique impact.
fn pair() -> Vec<Body> {
    let (r, t): (f64, f64) = (0.1, 0.002);
    let x0 = 0.5 * ((2.0 * r + t + 1e-4).powi(2) - (0.3 * r).powi(2)).sqrt();
    let a = sphere(
        0,
        r,
        t,
        3,
        Vec3::new(-x0, -0.3 * r, 0.0),
        Vec3::new(3.0, 0.0, 0.0),
    );
    let mut b = sphere(
        2,
        r,
        t,
        3,
        Vec3::new(x0, 0.0, 0.0),
        Vec3::new(-3.0, 0.0, 0.0),
    );
    let c = b.centre_of_mass();
    b.set_rigid_velocity(Vec3::new(-3.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 30.0), c);
    vec![a, b]
}

/// An unrelated body far away: coarser (larger stable step, so the global step is the
/// pair's), moving, with contact on; its id sits between the pair's.
fn bystander() -> Body {
    sphere(
        1,
        0.1,
        0.002,
        2,
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    )
}

fn run(bodies: Vec<Body>, steps: usize) -> Run {
    run_with(bodies, steps, ContactPass::Nodes)
}

fn run_with(bodies: Vec<Body>, steps: usize, pass: ContactPass) -> Run {
    let cfg = ContactConfig {
        margin: 1e-3,
        pass,
        ..Default::default()
    };
    let mut run = Run::new(
        group(bodies, cfg),
        RunConfig {
            end_time: 1.0,
            ..Default::default()
        },
    )
    .expect("start");
    for _ in 0..steps {
        run.step().expect("step");
    }
    run
}

const STEPS: usize = 300;

#[test]
fn contact_state_is_bit_identical_for_1_2_and_4_threads() {
    same_bits_for_1_2_and_4_threads(ContactPass::Nodes);
}

#[test]
fn segment_pass_state_is_bit_identical_for_1_2_and_4_threads() {
    same_bits_for_1_2_and_4_threads(ContactPass::Segments);
}

fn same_bits_for_1_2_and_4_threads(pass: ContactPass) {
    let hashes: Vec<u64> = [1, 2, 4]
        .iter()
        .map(|&n| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .expect("pool");
            pool.install(|| {
                let r = run_with(pair(), STEPS, pass);
                let active: usize = r.group.contact_stats().iter().map(|s| s.active_nodes).sum();
                println!(
                    "{n} threads: hash {:016x}, active contact nodes {active}",
                    state_hash(&r.group.bodies)
                );
                assert!(
                    active > 0,
                    "still in contact at the end: the hash covers contact"
                );
                state_hash(&r.group.bodies)
            })
        })
        .collect();
    assert_eq!(hashes[0], hashes[1]);
    assert_eq!(hashes[0], hashes[2]);
}

#[test]
fn a_pair_gives_the_same_bits_with_an_unrelated_body_in_its_group() {
    let alone = run(pair(), STEPS);
    let mut bodies = pair();
    bodies.insert(1, bystander());
    let shared = run(bodies, STEPS);
    let ha = state_hash(&alone.group.bodies);
    let hs = state_hash([&shared.group.bodies[0], &shared.group.bodies[2]]);
    println!(
        "alone {ha:016x}, with bystander {hs:016x}; steps {} / {}",
        alone.clock.step, shared.clock.step
    );
    assert_eq!(alone.clock.time.to_bits(), shared.clock.time.to_bits());
    assert_eq!(ha, hs);
    assert_eq!(
        alone.group.contact_stats(),
        &shared.group.contact_stats()[..1]
    );
}

#[test]
fn dropping_the_search_caches_mid_run_changes_nothing() {
    // what deserializing a group does (the caches are #[serde(skip)]): trees are then
    // rebuilt at other steps than in the uninterrupted run
    let whole = run(pair(), STEPS);
    let mut copy = run(pair(), STEPS / 2 + 13);
    copy.group.contact_state = ContactState::default();
    for _ in 0..STEPS - STEPS / 2 - 13 {
        copy.step().expect("step");
    }
    println!(
        "tree builds: uninterrupted {}, after the reset {}",
        whole.group.contact_state.tree_builds(),
        copy.group.contact_state.tree_builds()
    );
    assert_eq!(
        state_hash(&copy.group.bodies),
        state_hash(&whole.group.bodies)
    );
}
