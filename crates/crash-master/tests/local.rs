//! Local mode: the master loop over in-process workers gives the same bits as the
//! single-process core driver, whatever the number of workers.
#![allow(clippy::unwrap_used)] // a test panics on failure

mod common;

use common::{driver_reference, input, rows};
use crash_master::{run_local, CostModel, RecordSink, RunOptions};

const SCENE: &str = "ten-spheres-tiny.toml";

fn opts() -> RunOptions {
    RunOptions {
        cost: CostModel::Estimated,
        ..RunOptions::default()
    }
}

#[test]
fn local_workers_match_the_core_driver_bit_for_bit() {
    let inp = input(SCENE);
    let (ref_rows, ref_hash) = driver_reference(&inp);
    let mut results = Vec::new();
    for workers in [1, 3] {
        let mut sink = RecordSink::default();
        let stats = run_local(inp.clone(), workers, &mut sink, &opts()).unwrap();
        assert_eq!(stats.final_hash, sink.last_hash.unwrap());
        results.push((workers, stats, rows(&sink)));
    }
    for (workers, stats, rows) in &results {
        assert_eq!(
            rows.len(),
            ref_rows.len(),
            "{workers} workers: number of energy rows"
        );
        assert!(
            rows == &ref_rows,
            "{workers} workers: energy rows differ from the driver"
        );
        assert_eq!(
            stats.final_hash, ref_hash,
            "{workers} workers: final state hash"
        );
    }
    let (_, s3, _) = &results[1];
    // The scene exercises the distributed machinery: groups merged, bodies moved.
    assert!(s3.group_changes > 0, "no MEIM change in the test scene");
    eprintln!(
        "steps {}, groups max {}, final groups {:?}, migrations {}",
        s3.steps,
        s3.max_groups,
        s3.final_groups,
        s3.migrations.len()
    );
}
