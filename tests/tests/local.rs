//! Local mode: the master loop over in-process workers gives the same bits as the
//! single-process core driver, whatever the number of workers.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_master::{CostModel, RecordSink, RunOptions};
use crash_tests::runs::run_local;
use crash_tests::runs::{driver_reference, input, rows};

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

/// A physical fault inside a worker stops the run with exactly the driver's fault,
/// whatever the number of workers (here: tunnelling, a sphere thrown far too fast for
/// a tiny contact margin).
#[test]
fn a_fault_in_a_worker_is_the_drivers_fault() {
    let text = std::fs::read_to_string(crash_tests::fixtures::test_scene("two-spheres-tiny.toml"))
        .unwrap()
        .replace(
            "penalty_scale = 0.1",
            "penalty_scale = 0.1\nmargin = 1.0e-5",
        )
        .replace("velocity = [5.0, 0.0, 0.0]", "velocity = [400.0, 0.0, 0.0]");
    let scene = crash_scene::parse(&text, "fast.toml").unwrap();
    let inp = crash_master::RunInput::from_built(scene.build().unwrap());
    let mut g = crash_core::Group::new(inp.bodies.all().unwrap(), inp.gravity);
    g.contact = inp.contact;
    let expected = crash_core::driver::Run::new(g, inp.config)
        .unwrap()
        .run(|_| {})
        .unwrap_err();
    assert!(
        matches!(expected, crash_core::Fault::Tunnelling { .. }),
        "{expected}"
    );
    for workers in [1, 2] {
        let mut sink = RecordSink::default();
        let err = run_local(inp.clone(), workers, &mut sink, &opts()).unwrap_err();
        match &err {
            crash_master::MasterError::Fault(f) => assert_eq!(f, &expected),
            other => panic!("{workers} workers: {other}"),
        }
        assert_eq!(err.to_string(), expected.to_string());
        assert!(matches!(sink.finished, Some(Err(_))));
    }
}
