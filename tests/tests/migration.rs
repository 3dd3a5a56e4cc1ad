//! Migration: bodies that start on different workers and collide end up in one group
//! on one worker; after they separate the group splits and the parts are spread over
//! the workers again; the results stay bit-identical to one worker.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_master::{CostModel, Migration, RecordSink, RunOptions};
use crash_tests::runs::run_local;
use crash_tests::runs::{driver_reference, input, rows};

#[test]
fn colliding_bodies_join_one_worker_and_spread_again_after_separation() {
    let inp = input("two-spheres-tiny.toml");
    let (ref_rows, ref_hash) = driver_reference(&inp);
    let opts = RunOptions {
        cost: CostModel::Estimated,
        split_after: 20,
        ..RunOptions::default()
    };
    let mut sink = RecordSink::default();
    let stats = run_local(inp, 2, &mut sink, &opts).unwrap();

    // MEIM history: apart at the start, one edge while they meet, apart at the end.
    let first = &sink.contacts[0];
    assert_eq!(
        first,
        &(0, vec![]),
        "the spheres start out of each other's margin"
    );
    let met = sink
        .contacts
        .iter()
        .find(|(_, p)| p == &vec![(0, 1)])
        .unwrap()
        .0;
    let parted = sink
        .contacts
        .iter()
        .rev()
        .find(|(_, p)| p.is_empty())
        .unwrap()
        .0;
    assert!(0 < met && met < parted, "met at {met}, parted at {parted}");
    // Contact really happened (energy went through the contact term) and ended.
    assert!(sink.energy.iter().any(|r| r.totals.contact.abs() > 1e-3));

    // Start: one sphere per worker. Merge: the second sphere moves to the first's
    // worker right after the step that joined them. Split: one moves back out.
    let m = &stats.migrations;
    assert_eq!(m.len(), 2, "migrations: {m:?}");
    assert_eq!(
        m[0],
        Migration {
            step: met,
            body: 1,
            from: 1,
            to: 0
        }
    );
    assert_eq!(m[1].step, parted);
    assert_ne!(m[1].from, m[1].to);
    let workers: Vec<usize> = stats.final_groups.iter().map(|(_, w)| *w).collect();
    assert_eq!(stats.final_groups.len(), 2);
    assert_ne!(
        workers[0], workers[1],
        "final groups {:?}",
        stats.final_groups
    );

    // Bit-identical to the single-process driver (and so to one worker).
    assert!(
        rows(&sink) == ref_rows,
        "energy rows differ from the single-group driver"
    );
    assert_eq!(stats.final_hash, ref_hash);
}
