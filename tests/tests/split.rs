//! Groups split over workers by elements (issue 16 point 2): the master loop over
//! in-process workers with a group cut into parts on several workers gives the state
//! hash of the single-process core driver, bit for bit (the showcase, many spheres on one
//! deformable plate, and a scene whose groups change, so split groups are merged back
//! and split again).
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_master::{CostModel, RecordSink, RunInput, RunOptions, SplitMode};
use crash_tests::procs::{master, out_dir, worker};
use crash_tests::runs::{driver_reference, input, input_of, run_local};
use std::path::PathBuf;
use std::time::Duration;

fn opts(split: SplitMode) -> RunOptions {
    RunOptions {
        cost: CostModel::Estimated,
        split,
        ..RunOptions::default()
    }
}

fn scene(rel: &str, end: f64) -> RunInput {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel);
    let mut inp = input_of(&p);
    inp.config.end_time = end;
    inp
}

/// The final state hash over `workers` in-process workers with `split`, and how many
/// splits were made.
fn split_run(inp: &RunInput, workers: usize, split: SplitMode) -> (u64, u64) {
    let mut sink = RecordSink::default();
    let stats = run_local(inp.clone(), workers, &mut sink, &opts(split)).unwrap();
    assert_eq!(Some(stats.final_hash), sink.last_hash);
    (stats.final_hash, stats.splits)
}

#[test]
fn the_showcase_split_over_two_workers_has_the_single_process_state() {
    let inp = scene("scenes/sphere-on-plate.toml", 1.2e-3);
    let (_, reference) = driver_reference(&inp);
    assert_eq!(format!("{reference:016x}"), "137893bb99bd4cec");
    let (hash, splits) = split_run(&inp, 2, SplitMode::Auto);
    assert!(splits >= 1, "the showcase's one group must be split");
    assert_eq!(format!("{hash:016x}"), format!("{reference:016x}"));
}

/// `crash-master --split auto` over 2 `crash-worker` processes (gRPC on loopback):
/// the showcase to 1.2 ms ends in the single-process state, and the log names the split.
#[test]
fn the_showcase_split_over_two_grpc_workers_has_the_single_process_state() {
    let out = out_dir("split-grpc");
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/sphere-on-plate.toml");
    let extra = [
        "--split",
        "auto",
        "--end-time",
        "1.2e-3",
        "--output-interval",
        "6e-4",
    ];
    let (mut m, url) = master(&p, 2, &out, &extra);
    let mut w: Vec<_> = (0..2).map(|_| worker(&url, 1, &[])).collect();
    assert!(m.wait(Duration::from_secs(600)).success(), "{}", m.log());
    for p in &mut w {
        assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    }
    assert!(
        m.log().contains("split over workers [0, 1]")
            || m.log().contains("split over workers [1, 0]"),
        "{}",
        m.log()
    );
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(s.fault.is_none(), "{:?}", s.fault);
    assert_eq!(s.final_state_hash, "137893bb99bd4cec");
}

#[test]
fn many_spheres_on_one_plate_split_over_two_workers_have_the_single_process_state() {
    let inp = scene("scenes/bench/spheres-on-deformable-plate.toml", 3e-4);
    let (_, reference) = driver_reference(&inp);
    let (hash, splits) = split_run(&inp, 2, SplitMode::Auto);
    assert!(splits >= 1, "the one group of 65 bodies must be split");
    assert_eq!(format!("{hash:016x}"), format!("{reference:016x}"));
}

#[test]
fn groups_split_merged_back_and_split_again_keep_the_single_process_state() {
    let inp = input("ten-spheres-tiny.toml");
    let (_, reference) = driver_reference(&inp);
    for workers in [2, 3] {
        let (hash, splits) = split_run(&inp, workers, SplitMode::Always);
        assert!(splits >= 2, "{workers} workers: {splits} splits");
        assert_eq!(hash, reference, "{workers} workers");
    }
}
