//! Issue 14, hardening (docs/reliability.md), on loopback processes: a worker that
//! holds the secret but reports what cannot be true is dropped and the run ends on the
//! honest worker with the fault-free hash. Every wait is bounded; children are killed on
//! drop.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_link::{Reply, Secret};
use crash_tests::fixtures::test_scene;
use crash_tests::procs::{master, master_env, out_dir, worker, worker_env};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

const SCENE: &str = "ten-spheres-tiny.toml";
const END_TIME: &str = "0.002";
const TIMEOUT: Duration = Duration::from_secs(240);
const SECRET: &str = "correct horse battery staple 42";

fn final_hash(dir: &Path) -> String {
    let s = crash_io::read_summary(dir.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(s.fault.is_none(), "{:?}", s.fault);
    s.final_state_hash
}

/// The run without fault on two workers.
fn reference_hash() -> String {
    let out = out_dir("hardening-reference");
    let (mut m, url) = master(&test_scene(SCENE), 2, &out, &["--end-time", END_TIME]);
    let _w: Vec<_> = (0..2).map(|_| worker(&url, 1, &[])).collect();
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    let h = final_hash(&out);
    let _ = std::fs::remove_dir_all(&out);
    h
}

/// Step reports seen by the lying worker.
static REPORTS: AtomicU64 = AtomicU64::new(0);

/// Honest for 300 reports, then one body's kinetic energy turns negative.
fn lie(reply: &mut Reply) {
    if let Reply::Report(rep) = reply {
        if REPORTS.fetch_add(1, Ordering::Relaxed) == 300 {
            if let Some(b) = rep.bodies.first_mut() {
                b.energy.kinetic = -1.0;
            }
        }
    }
}

#[test]
fn a_worker_reporting_negative_kinetic_energy_is_dropped_and_the_run_ends_with_the_fault_free_hash()
{
    let expected = reference_hash();
    let out = out_dir("hardening-liar");
    let secret_file = out.with_extension("secret");
    std::fs::write(&secret_file, SECRET).unwrap();
    let (mut m, url) = master_env(
        &test_scene(SCENE),
        2,
        &out,
        &[
            "--end-time",
            END_TIME,
            "--checkpoint-seconds",
            "0",
            "--checkpoint-every",
            "100",
            "--secret-file",
            secret_file.to_str().unwrap(),
        ],
        &[],
    );
    let mut honest = worker_env(&url, 1, &[], &[("CRASH_SECRET", SECRET)]);
    // the liar: this process, with the secret, through the worker's own client
    let mut opts = crash_worker::WorkerOptions::new(&url, 1);
    opts.connect_timeout = Duration::from_secs(30);
    opts.secret = Some(Secret::new(SECRET.as_bytes(), "test").unwrap());
    opts.tamper = Some(lie);
    let liar = std::thread::spawn(move || crash_worker::run(&opts));
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    let log = m.log();
    assert!(
        log.contains("reported what cannot be true: body")
            && log.contains("negative kinetic energy -1e0"),
        "{log}"
    );
    assert!(log.contains("continuing from step"), "{log}");
    assert!(
        REPORTS.load(Ordering::Relaxed) > 300,
        "the lie was never told"
    );
    assert_eq!(final_hash(&out), expected);
    // told why: by the Shutdown it reads, or on a closed stream
    let told = match liar.join().unwrap() {
        Ok(reason) => reason,
        Err(e) => e.to_string(),
    };
    assert!(told.contains("dropped"), "{told}");
    assert!(
        honest.wait(Duration::from_secs(30)).success(),
        "{}",
        honest.log()
    );
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_file(&secret_file);
}
