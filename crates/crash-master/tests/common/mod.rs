//! Shared helpers of the cluster tests.
#![allow(dead_code, clippy::unwrap_used)]

pub mod procs;

use crash_core::driver::Run;
use crash_core::{EnergyTotals, Group};
use crash_master::{RecordSink, RunInput};
use std::path::PathBuf;

pub fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/scenes")
        .join(name)
}

pub fn input(name: &str) -> RunInput {
    let scene = crash_scene::load(&scene_path(name)).unwrap();
    RunInput::from_built(scene.build().unwrap())
}

/// Exact bits of an energy row.
pub fn bits(time: f64, e: &EnergyTotals) -> [u64; 8] {
    [
        time.to_bits(),
        e.kinetic.to_bits(),
        e.internal.to_bits(),
        e.hourglass.to_bits(),
        e.contact.to_bits(),
        e.damping.to_bits(),
        e.external.to_bits(),
        e.balance_error.to_bits(),
    ]
}

pub fn rows(s: &RecordSink) -> Vec<[u64; 8]> {
    s.energy.iter().map(|r| bits(r.time, &r.totals)).collect()
}

/// The single-process reference: the core driver on one group of all bodies.
pub fn driver_reference(input: &RunInput) -> (Vec<[u64; 8]>, u64) {
    let mut g = Group::new(input.bodies.clone(), input.gravity);
    g.contact = input.contact;
    let mut run = Run::new(g, input.config).unwrap();
    let mut rows = vec![bits(0.0, &run.energy)];
    run.run(|r| rows.push(bits(r.time(), &r.energy))).unwrap();
    (rows, crash_core::hash::state_hash(&run.group.bodies))
}
