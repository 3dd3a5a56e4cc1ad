//! The same scene through the one time loop in every mode gives the state hash of the
//! single-thread run: `crash run` with 2 threads, `crash run` over 3 in-process
//! workers, and `crash-master` over 2 `crash-worker` processes on loopback. Each mode
//! is its own test; the reference (`crash run --threads 1`) is computed once.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_tests::fixtures::test_scene;
use crash_tests::procs::{bin, master, out_dir, worker, Proc};
use std::path::Path;
use std::sync::OnceLock;
use std::time::Duration;

const SCENE: &str = "ten-spheres-tiny.toml";
const TIMEOUT: Duration = Duration::from_secs(300);

/// `crash run SCENE ARGS` into a fresh directory; its summary's final state hash.
fn crash_run(tag: &str, args: &[&str]) -> String {
    let out = out_dir(&format!("modes-{tag}"));
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
    hash_of(&out)
}

fn hash_of(out: &Path) -> String {
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(s.fault.is_none(), "{:?}", s.fault);
    assert!(!s.final_state_hash.is_empty());
    s.final_state_hash
}

fn reference() -> &'static str {
    static R: OnceLock<String> = OnceLock::new();
    R.get_or_init(|| crash_run("ref", &["--threads", "1"]))
}

#[test]
fn two_local_threads_give_the_single_thread_state() {
    assert_eq!(crash_run("threads2", &["--threads", "2"]), reference());
}

#[test]
fn three_in_process_workers_give_the_single_thread_state() {
    assert_eq!(
        crash_run("workers3", &["--workers", "3", "--threads", "1"]),
        reference()
    );
}

#[test]
fn two_grpc_workers_give_the_single_thread_state() {
    let out = out_dir("modes-grpc");
    let (mut m, url) = master(&test_scene(SCENE), 2, &out, &[]);
    let mut w: Vec<_> = (0..2).map(|_| worker(&url, 1, &[])).collect();
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    for p in &mut w {
        assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    }
    assert_eq!(hash_of(&out), reference());
}
