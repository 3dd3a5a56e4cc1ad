//! A kinematic body moved by a prescribed *displacement* (not a velocity): the "lift"
//! plate of ten-spheres-tiny-press is pushed 2.5 mm up and 1 mm along x over 1 ms and
//! held, pressing into two spheres that sit in different groups. Every group that
//! touches it holds its own read-only copy, moved by the same law wherever it is; the
//! invariants: every mode gives the single-thread state, and the plate ends exactly at
//! x0 + D (the law's velocity is the curve's change over each step, so it cannot drift).
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_tests::fixtures::test_scene;
use crash_tests::procs::{bin, master, out_dir, worker, Proc};
use crash_tests::runs::input;
use std::path::{Path, PathBuf};
use std::time::Duration;

const SCENE: &str = "ten-spheres-tiny-press.toml";
const TIMEOUT: Duration = Duration::from_secs(300);
/// The scene's displacement of "lift" (its ramp ends before end_time).
const D: [f64; 3] = [0.001, 0.0, 0.0025];

fn crash_run(tag: &str, args: &[&str]) -> PathBuf {
    let out = out_dir(&format!("kinprog-{tag}"));
    let scene = test_scene(SCENE);
    let mut all = vec![
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--no-pictures",
    ];
    all.extend_from_slice(args);
    let mut p = Proc::spawn("crash", &bin("crash"), &all);
    assert!(p.wait(TIMEOUT).success(), "{}", p.log());
    out
}

fn hash_of(out: &Path) -> String {
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(s.fault.is_none(), "{:?}", s.fault);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    s.final_state_hash
}

/// The plate pressed the spheres: rcforc.csv has rows of a pair with "lift".
fn lift_touched(out: &Path) -> bool {
    let csv = std::fs::read_to_string(out.join("rcforc.csv")).unwrap();
    csv.lines().any(|l| l.split(',').nth(2) == Some("lift"))
}

/// Largest |x - x0 - D| over the lift's nodes in the last frame [m].
fn lift_error(out: &Path) -> f64 {
    let mut frames: Vec<PathBuf> = std::fs::read_dir(out.join("frames"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "vtu"))
        .collect();
    frames.sort();
    let last = crash_io::read_vtu(frames.last().unwrap()).unwrap();
    // .vtu files keep body ids, not names
    let id = input(SCENE)
        .briefs
        .iter()
        .find(|b| b.name == "lift")
        .unwrap()
        .id;
    let lift = last.bodies.iter().find(|b| b.id == id).unwrap();
    lift.x
        .iter()
        .zip(&lift.x0)
        .flat_map(|(x, x0)| (0..3).map(move |d| (x[d] - x0[d] - D[d]).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn a_displaced_kinematic_plate_gives_the_single_thread_state_in_every_mode() {
    let one = crash_run("ref", &["--threads", "1"]);
    let reference = hash_of(&one);
    assert!(lift_touched(&one), "the press never touched a sphere");
    let two = crash_run("threads2", &["--threads", "2"]);
    assert_eq!(hash_of(&two), reference, "2 threads");
    let three = crash_run("workers3", &["--workers", "3", "--threads", "1"]);
    assert_eq!(hash_of(&three), reference, "3 in-process workers");

    let out = out_dir("kinprog-grpc");
    let (mut m, url) = master(&test_scene(SCENE), 2, &out, &[]);
    let mut w: Vec<_> = (0..2).map(|_| worker(&url, 1, &[])).collect();
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    for p in &mut w {
        assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    }
    assert_eq!(hash_of(&out), reference, "master + 2 gRPC workers");
}

#[test]
fn a_displaced_kinematic_plate_ends_at_its_prescribed_displacement() {
    for (tag, args) in [
        ("end1", &["--threads", "1"][..]),
        ("end3", &["--workers", "3", "--threads", "1"][..]),
    ] {
        let out = crash_run(tag, args);
        // 665 steps of round-off on a 0.35 m coordinate: far below a micrometre
        let err = lift_error(&out);
        eprintln!("{tag}: largest |x - x0 - D| {err:e} m");
        assert!(
            err < 1e-12,
            "{tag}: lift off its prescribed place by {err:e} m"
        );
    }
}
