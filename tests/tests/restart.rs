//! Restart from a checkpoint continues a run bit-identically (local workers).
#![allow(clippy::unwrap_used)]

use crash_master::{CostModel, MasterError, RecordSink, RunOptions};
use crash_tests::fixtures::test_scene;
use crash_tests::procs::{master, out_dir, worker};
use crash_tests::runs::run_local;
use crash_tests::runs::{input, resume_local, rows};
use std::time::Duration;

fn opts(every: u64) -> RunOptions {
    RunOptions {
        cost: CostModel::Estimated,
        split_after: 20,
        checkpoint_every: every,
        ..RunOptions::default()
    }
}

/// Every checkpoint of a run (taken before, during and after the spheres' contact,
/// with the MEIM edge alive or waiting to split), written to a file and read back,
/// continues with 1 and 2 workers to exactly the uninterrupted run's energy rows,
/// MEIM changes, contact statistics, frame schedule and final state hash.
#[test]
fn resumed_runs_match_the_uninterrupted_run_bit_for_bit() {
    let mut full = RecordSink::default();
    let stats = run_local(input("two-spheres-tiny.toml"), 2, &mut full, &opts(40)).unwrap();
    let all = rows(&full);
    assert!(full.checkpoints.len() >= 5, "{}", full.checkpoints.len());
    assert!(full.checkpoints.iter().any(|c| !c.edges.is_empty()));
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("master-restart-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("state.ckp");
    for (k, ck) in full.checkpoints.iter().enumerate() {
        crash_io::write_checkpoint(&path, ck).unwrap();
        let ck: crash_master::MasterCheckpoint = crash_io::read_checkpoint(&path).unwrap();
        let s = ck.clock.step as usize;
        let workers = 1 + k % 2;
        let mut rest = RecordSink::default();
        let st = resume_local(
            input("two-spheres-tiny.toml"),
            ck,
            workers,
            &mut rest,
            &opts(0),
        )
        .unwrap();
        assert_eq!(rows(&rest), all[s + 1..], "checkpoint at step {s}");
        assert_eq!(rest.last_hash, full.last_hash, "checkpoint at step {s}");
        assert_eq!(st.final_hash, stats.final_hash);
        assert_eq!(st.steps, stats.steps);
        assert_eq!(st.frames, stats.frames);
        assert_eq!(
            st.max_energy_error.to_bits(),
            stats.max_energy_error.to_bits()
        );
        let later = |v: &[(u64, f64, u64)]| {
            v.iter()
                .filter(|f| f.0 > s as u64)
                .copied()
                .collect::<Vec<_>>()
        };
        assert_eq!(rest.frames, later(&full.frames));
        let later_c: Vec<_> = full
            .contacts
            .iter()
            .filter(|c| c.0 > s as u64)
            .cloned()
            .collect();
        assert_eq!(rest.contacts, later_c, "MEIM changes after step {s}");
        let later_s: Vec<_> = full
            .contact_stats
            .iter()
            .filter(|c| c.0 > s as u64)
            .cloned()
            .collect();
        assert_eq!(rest.contact_stats, later_s);
    }
}

#[test]
fn checkpoint_of_another_scene_is_refused() {
    let mut full = RecordSink::default();
    run_local(input("two-spheres-tiny.toml"), 1, &mut full, &opts(100)).unwrap();
    let ck = full.checkpoints[0].clone();
    let mut rest = RecordSink::default();
    let err = resume_local(input("ten-spheres-tiny.toml"), ck, 1, &mut rest, &opts(0)).unwrap_err();
    assert!(matches!(err, MasterError::Input(_)), "{err}");
    assert!(err.to_string().contains("another scene"), "{err}");
}

/// A checkpoint written by crash-master over 2 worker processes continues in one
/// process (local workers) to the remote run's final state hash.
#[test]
fn remote_checkpoint_resumes_locally_to_the_same_final_state() {
    let out = out_dir("restart-remote");
    let scene = test_scene("two-spheres-tiny.toml");
    let (mut m, url) = master(
        &scene,
        2,
        &out,
        &["--checkpoint-every", "300", "--estimated-costs"],
    );
    let mut w: Vec<_> = (0..2).map(|_| worker(&url, 1, &[])).collect();
    assert!(m.wait(Duration::from_secs(120)).success(), "{}", m.log());
    for p in &mut w {
        assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    }
    let remote = crash_io::read_summary(out.join("summary.json")).unwrap();
    let r = crash_master::read_restart(&out.join(crash_master::RESTART_FILE)).unwrap();
    assert!(r.master.clock.step >= 300 && r.master.clock.step < remote.steps);
    let mut rest = RecordSink::default();
    let st = resume_local(
        input("two-spheres-tiny.toml"),
        r.master,
        1,
        &mut rest,
        &RunOptions::default(),
    )
    .unwrap();
    assert_eq!(crash_io::hash_hex(st.final_hash), remote.final_state_hash);
    assert_eq!(st.steps, remote.steps);
}
