//! `crash-master --resume` continues a cluster run from its checkpoint on another
//! number of worker processes and ends with the final state hash, and the same
//! energy.csv, as the run that was never interrupted: the clock travels in the
//! checkpoint and in every step, and a group computes the same bits on any worker.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_tests::fixtures::test_scene;
use crash_tests::procs::{master, out_dir, worker_env};
use std::path::Path;
use std::time::Duration;

const SCENE: &str = "two-spheres-tiny.toml";
const TIMEOUT: Duration = Duration::from_secs(180);

/// crash-master over `workers` worker processes with `extra` arguments and these
/// environment variables set for the workers.
fn cluster_env(out: &Path, workers: usize, extra: &[&str], env: &[(&str, &str)]) -> String {
    let (mut m, url) = master(&test_scene(SCENE), workers, out, extra);
    let mut w: Vec<_> = (0..workers)
        .map(|_| worker_env(&url, 1, &[], env))
        .collect();
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    for p in &mut w {
        assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    }
    m.log()
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let dest = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &dest);
        } else {
            std::fs::copy(e.path(), dest).unwrap();
        }
    }
}

/// The whole run on `before` workers with checkpoints; then the run resumed from its
/// last checkpoint (a copy of the run directory) on `after` workers.
fn resume_changes_nothing(tag: &str, before: usize, after: usize) {
    resume_with(tag, &[], (before, &[]), (after, &[]));
}

/// `resume_changes_nothing` with `extra` arguments for both runs and environment
/// variables for the workers of each.
fn resume_with(
    tag: &str,
    extra: &[&str],
    before: (usize, &[(&str, &str)]),
    after: (usize, &[(&str, &str)]),
) {
    let full = out_dir(&format!("resume-{tag}-full"));
    let args = [&["--checkpoint-every", "250"][..], extra].concat();
    cluster_env(&full, before.0, &args, before.1);
    let summary = crash_io::read_summary(full.join(crash_io::SUMMARY_JSON)).unwrap();
    let ckp = crash_master::read_restart(&full.join(crash_master::RESTART_FILE)).unwrap();
    let at = ckp.master.clock.step;
    assert!(at >= 250 && at < summary.steps, "checkpoint at step {at}");

    let resumed = out_dir(&format!("resume-{tag}-resumed"));
    copy_dir(&full, &resumed);
    let ck = resumed.join(crash_master::RESTART_FILE);
    let log = cluster_env(
        &resumed,
        after.0,
        &["--resume", ck.to_str().unwrap()],
        after.1,
    );
    assert!(log.contains(&format!("resuming from step {at}")), "{log}");
    let again = crash_io::read_summary(resumed.join(crash_io::SUMMARY_JSON)).unwrap();
    assert_eq!(again.final_state_hash, summary.final_state_hash);
    assert_eq!(again.steps, summary.steps);
    let energy = |d: &Path| std::fs::read_to_string(d.join(crash_io::ENERGY_CSV)).unwrap();
    assert_eq!(
        energy(&resumed),
        energy(&full),
        "energy rows, byte for byte"
    );
}

#[test]
fn a_run_resumed_on_fewer_workers_ends_as_the_uninterrupted_run() {
    resume_changes_nothing("2to1", 2, 1);
}

#[test]
fn a_run_resumed_on_more_workers_ends_as_the_uninterrupted_run() {
    resume_changes_nothing("1to3", 1, 3);
}

/// Forces carried as node sums (crash_core::summed, forced in every worker by
/// CRASH_SUMMED=1) leave in the checkpoint settled into the slots: the run resumed on
/// workers that gather the slots (CRASH_SUMMED=0) ends as the uninterrupted run. The
/// spheres' group is not split (parts carry slots), so the last checkpoint, after the
/// impact, holds ringing spheres whose forces were carried as node sums.
#[test]
fn a_checkpoint_of_forces_carried_as_node_sums_resumes_to_the_uninterrupted_run() {
    resume_with(
        "summed",
        &["--split", "off"],
        (2, &[("CRASH_SUMMED", "1")]),
        (1, &[("CRASH_SUMMED", "0")]),
    );
}
