//! `crash-worker --probe URL`: the master's gRPC health service answers SERVING for
//! crash.v1.Coordinator while it waits for its workers; nothing listening
//! (or the master gone) is a failure.
#![allow(clippy::unwrap_used)]

use crash_tests::fixtures::test_scene;
use crash_tests::procs::{master, out_dir, worker, Proc};
use std::time::Duration;

fn probe(url: &str) -> (bool, String) {
    let mut p = Proc::spawn(
        "probe",
        &crash_tests::procs::worker_bin(),
        &["--probe", url, "--probe-timeout", "5"],
    );
    let ok = p.wait(Duration::from_secs(30)).success();
    (ok, p.log())
}

#[test]
fn probe_succeeds_against_a_running_master_and_fails_against_nothing() {
    let out = out_dir("probe");
    let (mut m, url) = master(&test_scene("two-spheres-tiny.toml"), 1, &out, &[]);
    // waiting for its worker: serving
    let (ok, log) = probe(&url);
    assert!(ok, "{log}");
    assert!(log.contains("is serving"), "{log}");
    // the run itself, then the master exits: nothing listens on its port any more
    let mut w = worker(&url, 1, &[]);
    assert!(m.wait(Duration::from_secs(120)).success(), "{}", m.log());
    assert!(w.wait(Duration::from_secs(30)).success(), "{}", w.log());
    let (ok, log) = probe(&url);
    assert!(!ok, "{log}");
    assert!(log.contains("cannot reach the master at"), "{log}");
}
