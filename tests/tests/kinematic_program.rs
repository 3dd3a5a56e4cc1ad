//! A kinematic body moved by a prescribed *displacement* (not a velocity): the "lift"
//! plate of ten-spheres-tiny-press is pushed 2.5 mm up and 1 mm along x over 1 ms and
//! held, pressing into two spheres that sit in different groups. Every group that
//! touches it holds its own read-only copy, moved by the same law wherever it is; the
//! invariants: every mode gives the single-thread state, and the plate ends exactly at
//! x0 + D (the law's velocity is the curve's change over each step, so it cannot drift).
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_tests::cli::{crash_run, final_hash, grpc_run, last_frame};
use crash_tests::fixtures::test_scene;
use crash_tests::runs::input;
use std::path::Path;

const SCENE: &str = "ten-spheres-tiny-press.toml";
/// The scene's displacement of "lift" (its ramp ends before end_time).
const D: [f64; 3] = [0.001, 0.0, 0.0025];

fn run(tag: &str, args: &[&str]) -> std::path::PathBuf {
    crash_run(&test_scene(SCENE), &format!("kinprog-{tag}"), args)
}

/// The final state hash of a run that ended without a warning.
fn hash_of(out: &Path) -> String {
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    final_hash(out)
}

/// The plate pressed the spheres: rcforc.csv has rows of a pair with "lift".
fn lift_touched(out: &Path) -> bool {
    let csv = std::fs::read_to_string(out.join("rcforc.csv")).unwrap();
    csv.lines().any(|l| l.split(',').nth(2) == Some("lift"))
}

/// Largest |x - x0 - D| over the lift's nodes in the last frame [m].
fn lift_error(out: &Path) -> f64 {
    // .vtu files keep body ids, not names
    let id = input(SCENE)
        .briefs
        .iter()
        .find(|b| b.name == "lift")
        .unwrap()
        .id;
    let last = last_frame(out);
    let lift = last.bodies.iter().find(|b| b.id == id).unwrap();
    lift.x
        .iter()
        .zip(&lift.x0)
        .flat_map(|(x, x0)| (0..3).map(move |d| (x[d] - x0[d] - D[d]).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn a_displaced_kinematic_plate_gives_the_single_thread_state_in_every_mode() {
    let one = run("ref", &["--threads", "1"]);
    let reference = hash_of(&one);
    assert!(lift_touched(&one), "the press never touched a sphere");
    let two = run("threads2", &["--threads", "2"]);
    assert_eq!(hash_of(&two), reference, "2 threads");
    let three = run("workers3", &["--workers", "3", "--threads", "1"]);
    assert_eq!(hash_of(&three), reference, "3 in-process workers");

    let out = grpc_run(&test_scene(SCENE), "kinprog-grpc", 2, &[]);
    assert_eq!(hash_of(&out), reference, "master + 2 gRPC workers");
}

#[test]
fn a_displaced_kinematic_plate_ends_at_its_prescribed_displacement() {
    for (tag, args) in [
        ("end1", &["--threads", "1"][..]),
        ("end3", &["--workers", "3", "--threads", "1"][..]),
    ] {
        let out = run(tag, args);
        // 665 steps of round-off on a 0.35 m coordinate: far below a micrometre
        let err = lift_error(&out);
        eprintln!("{tag}: largest |x - x0 - D| {err:e} m");
        assert!(
            err < 1e-12,
            "{tag}: lift off its prescribed place by {err:e} m"
        );
    }
}
