//! The step lane (protocol v14, docs/architecture-cluster.md) on loopback processes: a
//! run over the lane ends with the hash of the same run on the gRPC streams
//! (`--no-step-lane`), and strangers on the lane's port (garbage, a wrong session token,
//! silence) are refused without touching the run. Every wait is bounded; children are
//! killed on drop.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_link::lane::{opening, OPENING_LEN};
use crash_tests::fixtures::test_scene;
use crash_tests::procs::{master, out_dir, worker};
use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::time::Duration;

const SCENE: &str = "ten-spheres-tiny.toml";
const END_TIME: &str = "0.001";
const TIMEOUT: Duration = Duration::from_secs(240);

fn final_hash(dir: &Path) -> String {
    let s = crash_io::read_summary(dir.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(s.fault.is_none(), "{:?}", s.fault);
    s.final_state_hash
}

/// A two-worker run with `extra` master options and `worker_extra` worker options; its
/// hash and the master's log.
fn run(tag: &str, extra: &[&str], worker_extra: &[&str], strangers: bool) -> (String, String) {
    let out = out_dir(tag);
    let mut args = vec!["--end-time", END_TIME, "--handshake-timeout", "1"];
    args.extend_from_slice(extra);
    let (mut m, url) = master(&test_scene(SCENE), 2, &out, &args);
    let lane = m.expect_line("step lane", Duration::from_secs(30));
    if strangers {
        let addr = lane.rsplit(' ').next().unwrap().trim().to_string();
        // garbage, a lane opening with a wrong token, and one that says nothing
        let mut g = TcpStream::connect(&addr).unwrap();
        g.write_all(&[0x55; OPENING_LEN]).unwrap();
        let mut t = TcpStream::connect(&addr).unwrap();
        t.write_all(&opening(0, &[7; 32]).unwrap()).unwrap();
        let s = TcpStream::connect(&addr).unwrap();
        // closed by the master without its answer (the silent one after the
        // handshake deadline), while it waits for its workers
        for mut s in [g, t, s] {
            s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
            let mut b = [0u8; 1];
            assert_eq!(
                s.read(&mut b).unwrap_or(0),
                0,
                "a stranger's lane was taken"
            );
        }
    }
    let mut w: Vec<_> = (0..2).map(|_| worker(&url, 1, worker_extra)).collect();
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    for w in &mut w {
        assert!(w.wait(Duration::from_secs(30)).success(), "{}", w.log());
    }
    let h = final_hash(&out);
    let _ = std::fs::remove_dir_all(&out);
    (h, m.log())
}

#[test]
fn a_run_on_the_step_lane_has_the_hash_of_the_grpc_run_and_strangers_on_its_port_are_refused() {
    let (grpc, log) = run("lane-off", &["--no-step-lane"], &[], false);
    assert!(log.contains("step lane off"), "{log}");
    let (lane, log) = run("lane-on", &[], &[], true);
    assert_eq!(lane, grpc);
    assert!(
        !log.contains("did not open the step lane"),
        "the workers used the lane: {log}"
    );
    for why in [
        "not a step lane's opening",
        "wrong session token for worker 0",
        "no opening within",
    ] {
        assert!(log.contains(why), "refused ({why}): {log}");
    }
}

/// Workers that block at once for each command and halo (`--poll-us 0`) end with the
/// hash of workers that poll first (the default): how a worker waits changes no bit.
/// `--split always` so the halo wait between the workers is exercised too.
#[test]
fn workers_that_block_at_once_end_with_the_hash_of_polling_workers() {
    let split = ["--split", "always"];
    let (polling, _) = run("poll-on", &split, &[], false);
    let (blocking, log) = run("poll-off", &split, &["--poll-us", "0"], false);
    assert_eq!(blocking, polling);
    assert!(
        log.contains("split over workers"),
        "the group was split: {log}"
    );
}
