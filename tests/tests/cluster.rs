//! crash-master + crash-worker processes over gRPC on loopback: the same bits as the
//! local run; refusal of a protocol mismatch; without checkpoints a lost or silent
//! worker ends the run with a clear message (with them the run continues: faults.rs)
//! (bounded waits everywhere, children killed on drop).
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_master::{CostModel, RecordSink, RunOptions};
use crash_tests::fixtures::test_scene;
use crash_tests::procs::{master, out_dir, worker};
use crash_tests::runs::{bits, input, rows, rows as rows_of};
use crash_tests::runs::{contact_rows, run_local};
use std::path::Path;
use std::time::Duration;

const RUN_TIMEOUT: Duration = Duration::from_secs(180);

fn local_sink(scene: &str) -> (RecordSink, u64) {
    let opts = RunOptions {
        cost: CostModel::Estimated,
        ..RunOptions::default()
    };
    let mut sink = RecordSink::default();
    let stats = run_local(input(scene), 1, &mut sink, &opts).unwrap();
    (sink, stats.final_hash)
}

fn local(scene: &str) -> (Vec<[u64; 8]>, u64) {
    let (sink, hash) = local_sink(scene);
    (rows(&sink), hash)
}

/// energy.csv rows and the final hash of a finished run directory.
fn read_run(dir: &Path) -> (Vec<[u64; 8]>, u64, crash_io::Summary) {
    let rows = crash_io::read_energy_csv(dir.join(crash_io::ENERGY_CSV))
        .unwrap()
        .iter()
        .map(|r| bits(r.time, &r.energy))
        .collect();
    let s = crash_io::read_summary(dir.join(crash_io::SUMMARY_JSON)).unwrap();
    let h = u64::from_str_radix(&s.final_state_hash, 16).unwrap();
    (rows, h, s)
}

/// Run `scene` on a master and two worker processes with `threads` each.
type RunFiles = (
    Vec<[u64; 8]>,
    u64,
    crash_io::Summary,
    Vec<(u64, u32, u32, u64, u64)>,
);

fn remote(scene: &str, threads: usize, tag: &str) -> RunFiles {
    let out = out_dir(tag);
    let (mut m, url) = master(&test_scene(scene), 2, &out, &["--estimated-costs"]);
    let mut w1 = worker(&url, threads, &[]);
    let mut w2 = worker(&url, threads, &[]);
    let status = m.wait(RUN_TIMEOUT);
    assert!(status.success(), "master failed:\n{}", m.log());
    for w in [&mut w1, &mut w2] {
        let s = w.wait(Duration::from_secs(30));
        assert!(s.success(), "worker failed:\n{}", w.log());
        assert!(
            w.log().contains("done (the run is complete)"),
            "{}",
            w.log()
        );
    }
    let (rows, hash, summary) = read_run(&out);
    let contacts = crash_io::read_contacts_csv(out.join(crash_io::CONTACTS_CSV))
        .unwrap()
        .iter()
        .map(|r| {
            (
                r.time.to_bits(),
                r.a,
                r.b,
                r.force.to_bits(),
                r.penetration.to_bits(),
            )
        })
        .collect();
    let _ = std::fs::remove_dir_all(&out);
    (rows, hash, summary, contacts)
}

#[test]
fn two_worker_processes_match_the_local_run_bit_for_bit_with_1_and_2_threads() {
    let scene = "ten-spheres-tiny.toml";
    let (ref_rows, ref_hash) = local(scene);
    for threads in [1, 2] {
        let (rows, hash, summary, _) = remote(scene, threads, &format!("ten-{threads}"));
        assert_eq!(rows.len(), ref_rows.len(), "{threads} threads: energy rows");
        assert!(
            rows == ref_rows,
            "{threads} threads: energy rows differ from the local run"
        );
        assert_eq!(hash, ref_hash, "{threads} threads: final state hash");
        assert!(summary.fault.is_none());
    }
}

/// The CI smoke test: two workers, a small scene whose bodies migrate over the wire
/// (merge onto one worker, then spread again; crash-master's default `--split auto`
/// splits the group of the two spheres in contact over both), same hash and
/// contacts.csv as the local run.
#[test]
fn two_worker_smoke_with_migration_over_the_wire() {
    let scene = "two-spheres-tiny.toml";
    let (sink, ref_hash) = local_sink(scene);
    let (rows, hash, summary, contacts) = remote(scene, 1, "smoke");
    assert!(
        summary.cluster.splits >= 1,
        "the group in contact was not split"
    );
    assert!(
        rows == rows_of(&sink),
        "energy rows differ from the local run"
    );
    assert_eq!(hash, ref_hash);
    // contact statistics travel too: contacts.csv holds the local run's rows, exactly
    let ref_contacts = contact_rows(&sink);
    assert!(!ref_contacts.is_empty());
    assert!(
        contacts == ref_contacts,
        "contacts.csv differs from the local run"
    );
}

#[test]
fn protocol_version_mismatch_is_refused_clearly_on_both_sides() {
    let out = out_dir("version");
    let (mut m, url) = master(&test_scene("two-spheres-tiny.toml"), 1, &out, &[]);
    let mut w = worker(&url, 1, &["--protocol-version", "999"]);
    let status = w.wait(Duration::from_secs(60));
    assert!(!status.success());
    let wlog = w.log();
    assert!(
        wlog.contains("refused this worker: protocol version mismatch")
            && wlog.contains("v999")
            && wlog.contains(&format!("v{}", crash_link::PROTOCOL_VERSION)),
        "worker said:\n{wlog}"
    );
    m.expect_line("protocol version mismatch", Duration::from_secs(10));
    assert!(
        m.log().contains("refused worker"),
        "master said:\n{}",
        m.log()
    );
    m.kill();
    let _ = std::fs::remove_dir_all(&out);
}

/// Start a long run on two workers and wait until it is stepping.
fn long_run(
    tag: &str,
    extra: &[&str],
) -> (
    crash_tests::procs::Proc,
    crash_tests::procs::Proc,
    crash_tests::procs::Proc,
    std::path::PathBuf,
) {
    let out = out_dir(tag);
    let mut args = vec!["--end-time", "1.0"];
    args.extend_from_slice(extra);
    let (m, url) = master(&test_scene("ten-spheres-tiny.toml"), 2, &out, &args);
    let w1 = worker(&url, 1, &[]);
    let w2 = worker(&url, 1, &[]);
    m.expect_line("workers attached", Duration::from_secs(60));
    // let it write a few frames
    std::thread::sleep(Duration::from_millis(1500));
    (m, w1, w2, out)
}

fn frames_listed(out: &Path) -> usize {
    crash_io::read_pvd(&out.join(crash_io::PVD_FILE)).map_or(0, |v| v.len())
}

#[test]
fn a_killed_worker_ends_the_run_with_a_clear_message() {
    // no checkpoint to go back to: the loss ends the run
    let (mut m, mut w1, mut w2, out) = long_run("killed", &["--checkpoint-seconds", "0"]);
    w2.kill();
    let status = m.wait(Duration::from_secs(60));
    assert!(!status.success());
    let log = m.log();
    assert!(
        log.contains("worker") && log.contains("disconnected"),
        "master said:\n{log}"
    );
    // the surviving worker is told to stop
    let s = w1.wait(Duration::from_secs(30));
    assert!(s.success(), "{}", w1.log());
    assert!(w1.log().contains("the run stopped"), "{}", w1.log());
    // the frames written before are kept, the summary names the cause
    assert!(frames_listed(&out) >= 1);
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(s.fault.unwrap().contains("disconnected"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_silent_worker_ends_the_run_after_the_reply_timeout() {
    // heartbeats off: the reply timeout, the safety net, still bounds the wait
    let (mut m, mut w1, w2, out) = long_run(
        "silent",
        &[
            "--reply-timeout",
            "2",
            "--heartbeat-timeout",
            "0",
            "--checkpoint-seconds",
            "0",
        ],
    );
    w2.signal("STOP");
    let status = m.wait(Duration::from_secs(60));
    assert!(!status.success());
    let log = m.log();
    assert!(
        log.contains("stopped answering: no reply within 2.0 s"),
        "master said:\n{log}"
    );
    let s = w1.wait(Duration::from_secs(30));
    assert!(s.success(), "{}", w1.log());
    assert!(frames_listed(&out) >= 1);
    drop(w2);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn workers_exit_with_a_clear_message_when_the_master_dies() {
    let (mut m, mut w1, mut w2, out) = long_run("master-killed", &[]);
    m.kill();
    for w in [&mut w1, &mut w2] {
        let s = w.wait(Duration::from_secs(60));
        assert!(!s.success());
        assert!(
            w.log().contains("lost the master at http://127.0.0.1:"),
            "{}",
            w.log()
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// A physical fault in a worker process reaches the master intact (same text as the
/// single-process driver) and ends the run; the workers are told to stop.
#[test]
fn a_fault_in_a_worker_process_ends_the_run_with_the_drivers_message() {
    let out = out_dir("fault");
    let text = std::fs::read_to_string(test_scene("two-spheres-tiny.toml"))
        .unwrap()
        .replace(
            "penalty_scale = 0.1",
            "penalty_scale = 0.1\nmargin = 1.0e-5",
        )
        .replace("velocity = [5.0, 0.0, 0.0]", "velocity = [400.0, 0.0, 0.0]");
    let scene = out.join("fast.toml");
    std::fs::write(&scene, &text).unwrap();
    let inp = input_from(&scene);
    let mut g = crash_core::Group::new(inp.bodies.all().unwrap(), inp.gravity);
    g.contact = inp.contact;
    let expected = crash_core::driver::Run::new(g, inp.config)
        .unwrap()
        .run(|_| {})
        .unwrap_err()
        .to_string();
    let run_dir = out.join("run");
    let (mut m, url) = master(&scene, 2, &run_dir, &[]);
    let mut w1 = worker(&url, 1, &[]);
    let mut w2 = worker(&url, 1, &[]);
    assert!(!m.wait(RUN_TIMEOUT).success());
    assert!(
        m.log().contains(&expected),
        "expected '{expected}', master said:\n{}",
        m.log()
    );
    for w in [&mut w1, &mut w2] {
        assert!(w.wait(Duration::from_secs(30)).success(), "{}", w.log());
    }
    let s = crash_io::read_summary(run_dir.join(crash_io::SUMMARY_JSON)).unwrap();
    assert_eq!(s.fault.as_deref(), Some(expected.as_str()));
    let _ = std::fs::remove_dir_all(&out);
}

fn input_from(path: &Path) -> crash_master::RunInput {
    crash_master::RunInput::from_built(crash_scene::load(path).unwrap().build().unwrap())
}

/// Workers may start before the master: they retry with backoff until it listens.
#[test]
fn workers_started_before_the_master_attach_when_it_comes_up() {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let url = format!("http://127.0.0.1:{port}");
    let mut w1 = worker(&url, 1, &[]);
    let mut w2 = worker(&url, 1, &[]);
    std::thread::sleep(Duration::from_millis(1500));
    let out = out_dir("early");
    let listen = format!("127.0.0.1:{port}");
    let mut m = crash_tests::procs::Proc::spawn(
        "crash-master",
        &crash_tests::procs::master_bin(),
        &[
            test_scene("two-spheres-tiny.toml").to_str().unwrap(),
            "--listen",
            &listen,
            "--workers",
            "2",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert!(m.wait(RUN_TIMEOUT).success(), "{}", m.log());
    for w in [&mut w1, &mut w2] {
        assert!(w.wait(Duration::from_secs(30)).success(), "{}", w.log());
    }
    let _ = std::fs::remove_dir_all(&out);
}
