//! A scene run in each in-process mode, with its energy rows (exact bits) and state
//! hash: the core driver on one group (the reference), and the master loop over
//! in-process workers (what `crash run` runs).

use crate::fixtures::test_scene;
use crash_core::driver::Run;
use crash_core::{EnergyTotals, Group};
use crash_master::{MasterError, RecordSink, RunInput, RunOptions, RunStats, Sink};
use crash_worker::InProcess;
use std::path::Path;

/// The run input of a scene file.
pub fn input_of(path: &Path) -> RunInput {
    let scene = crash_scene::load(path).unwrap();
    RunInput::from_built(scene.build().unwrap())
}

/// The run input of a scene of the test suite (`tests/scenes/`).
pub fn input(name: &str) -> RunInput {
    input_of(&test_scene(name))
}

/// The master loop over `workers` in-process workers (local mode, as `crash run`: all
/// but the last on threads of their own).
pub fn run_local(
    input: RunInput,
    workers: usize,
    sink: &mut dyn Sink,
    opts: &RunOptions,
) -> Result<RunStats, MasterError> {
    crash_master::run_with(input, &mut in_process(workers), sink, opts)
}

/// `workers` in-process workers as `crash run` starts them (all but the last on
/// threads of their own), one compute thread each.
pub fn in_process(workers: usize) -> Vec<InProcess> {
    InProcess::many(workers, 1).expect("in-process worker threads")
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

/// Exact bits of the contacts.csv rows (pairs with pushed nodes): time, bodies,
/// normal force, deepest penetration.
pub fn contact_rows(sink: &RecordSink) -> Vec<(u64, u32, u32, u64, u64)> {
    let mut out = Vec::new();
    for (_, time, stats) in &sink.contact_stats {
        for s in stats.iter().filter(|s| s.active_nodes > 0) {
            out.push((
                time.to_bits(),
                s.a,
                s.b,
                s.normal_force.to_bits(),
                s.max_penetration.to_bits(),
            ));
        }
    }
    out
}

/// The single-process reference: the core driver on one group of all bodies.
pub fn driver_reference(input: &RunInput) -> (Vec<[u64; 8]>, u64) {
    let mut g = Group::new(input.bodies.all().unwrap(), input.gravity);
    g.contact = input.contact;
    let mut run = Run::new(g, input.config).unwrap();
    let mut rows = vec![bits(0.0, &run.energy)];
    run.run(|r| rows.push(bits(r.time(), &r.energy))).unwrap();
    (rows, crash_core::hash::state_hash(&run.group.bodies))
}

/// The master loop from a checkpoint over `workers` in-process workers.
pub fn resume_local(
    input: RunInput,
    state: crash_master::MasterCheckpoint,
    workers: usize,
    sink: &mut dyn Sink,
    opts: &RunOptions,
) -> Result<RunStats, MasterError> {
    crash_master::resume_with(input, state, &mut in_process(workers), sink, opts)
}
