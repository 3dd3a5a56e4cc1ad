//! Whole runs as a user starts them (`crash run`, `crash-master` + `crash-worker`), and
//! what tests read back from their output directories.

use crate::procs::{bin, master, out_dir, worker_env, Proc};
use crash_io::Frame;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Longest a test run may take.
pub const TIMEOUT: Duration = Duration::from_secs(300);

/// `crash run SCENE ARGS` into a fresh directory named after `tag` (quiet, no pictures);
/// panics with its log unless it exits 0. Returns the directory.
pub fn crash_run(scene: &Path, tag: &str, args: &[&str]) -> PathBuf {
    crash_run_env(scene, tag, args, &[])
}

/// As `crash_run`, with these environment variables set.
pub fn crash_run_env(scene: &Path, tag: &str, args: &[&str], env: &[(&str, &str)]) -> PathBuf {
    let out = out_dir(tag);
    let mut all = vec![
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--no-pictures",
    ];
    all.extend_from_slice(args);
    let mut p = Proc::spawn_env("crash", &bin("crash"), &all, env);
    assert!(p.wait(TIMEOUT).success(), "{}", p.log());
    out
}

/// `crash-master SCENE` with `workers` `crash-worker` processes of one thread each on
/// loopback, into a fresh directory; panics unless all exit 0. Returns the directory.
pub fn grpc_run(scene: &Path, tag: &str, workers: usize, extra: &[&str]) -> PathBuf {
    grpc_run_env(scene, tag, workers, extra, &[])
}

/// As `grpc_run`, with these environment variables set for the workers.
pub fn grpc_run_env(
    scene: &Path,
    tag: &str,
    workers: usize,
    extra: &[&str],
    env: &[(&str, &str)],
) -> PathBuf {
    let out = out_dir(tag);
    let (mut m, url) = master(scene, workers, &out, extra);
    let mut w: Vec<_> = (0..workers)
        .map(|_| worker_env(&url, 1, &[], env))
        .collect();
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    for p in &mut w {
        assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    }
    out
}

/// The final state hash in a run's summary.json (panics on a fault).
pub fn final_hash(out: &Path) -> String {
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(s.fault.is_none(), "{:?}", s.fault);
    assert!(!s.final_state_hash.is_empty());
    s.final_state_hash
}

/// The last frame a run wrote (frames/*.vtu, by name).
pub fn last_frame(out: &Path) -> Frame {
    let mut frames: Vec<PathBuf> = std::fs::read_dir(out.join("frames"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "vtu"))
        .collect();
    frames.sort();
    crash_io::read_vtu(frames.last().unwrap()).unwrap()
}
