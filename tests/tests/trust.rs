//! Only its own workers (docs/reliability.md): loopback processes. A worker without
//! the secret or with a wrong one is refused and takes no slot; the real worker then
//! runs the scene to the open run's final hash; a peer announcing a huge message before
//! Hello is refused without the master's memory growing; an idle TCP connection is
//! closed after the handshake timeout; peer text reaches the log escaped. And the
//! message limit is measured against the largest real message.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_tests::fixtures::test_scene;
use crash_tests::procs::{master, master_env, out_dir, proc_status_kb, worker, worker_env};
use std::io::Read;
use std::path::Path;
use std::time::{Duration, Instant};

const RUN_TIMEOUT: Duration = Duration::from_secs(180);
const SCENE: &str = "two-spheres-tiny.toml";
const SECRET: &str = "correct horse battery staple 42";

fn final_hash(dir: &Path) -> u64 {
    let s = crash_io::read_summary(dir.join(crash_io::SUMMARY_JSON)).unwrap();
    u64::from_str_radix(&s.final_state_hash, 16).unwrap()
}

/// The open run (no secret): its final hash.
fn open_run_hash() -> u64 {
    let out = out_dir("trust-open");
    let (mut m, url) = master(&test_scene(SCENE), 1, &out, &["--estimated-costs"]);
    m.expect_line("warning: no shared secret", Duration::from_secs(10));
    let mut w = worker(&url, 1, &[]);
    assert!(m.wait(RUN_TIMEOUT).success(), "{}", m.log());
    assert!(w.wait(Duration::from_secs(30)).success(), "{}", w.log());
    let h = final_hash(&out);
    let _ = std::fs::remove_dir_all(&out);
    h
}

#[test]
fn workers_without_the_secret_or_with_a_wrong_one_are_refused_and_the_real_one_runs() {
    let reference = open_run_hash();
    let out = out_dir("trust-secret");
    let secret_file = out.with_extension("secret");
    std::fs::write(&secret_file, format!("{SECRET}\n")).unwrap();
    let (mut m, url) = master_env(
        &test_scene(SCENE),
        1,
        &out,
        &[
            "--estimated-costs",
            "--secret-file",
            secret_file.to_str().unwrap(),
        ],
        &[],
    );
    m.expect_line(
        "workers must prove the shared secret",
        Duration::from_secs(10),
    );
    // no secret: refused, with a message on both sides
    let mut none = worker(&url, 1, &[]);
    assert!(!none.wait(Duration::from_secs(30)).success());
    assert!(
        none.log().contains("refused this worker")
            && none
                .log()
                .contains("has none: start crash-worker with --secret-file"),
        "{}",
        none.log()
    );
    m.expect_line("refused worker", Duration::from_secs(10));
    // a wrong secret (from the environment), and a host name with escape codes
    let mut wrong = worker_env(
        &url,
        1,
        &["--host", "evil\u{1b}[2J\rdone\u{202e}"],
        &[("CRASH_SECRET", "not the secret of this cluster")],
    );
    assert!(!wrong.wait(Duration::from_secs(30)).success());
    assert!(
        wrong.log().contains("proof of the shared secret is wrong"),
        "{}",
        wrong.log()
    );
    let line = m.expect_line(
        "proof of the shared secret is wrong",
        Duration::from_secs(10),
    );
    assert!(
        line.contains("evil\\u{1b}[2J\\u{d}done\\u{202e}") && !line.contains('\u{1b}'),
        "peer text not escaped: {line:?}"
    );
    // the real worker (secret from the environment) takes the one slot
    let mut real = worker_env(&url, 1, &[], &[("CRASH_SECRET", SECRET)]);
    assert!(m.wait(RUN_TIMEOUT).success(), "{}", m.log());
    assert!(
        real.wait(Duration::from_secs(30)).success(),
        "{}",
        real.log()
    );
    assert!(
        !m.log().contains('\u{1b}'),
        "an escape code reached the log"
    );
    assert_eq!(
        final_hash(&out),
        reference,
        "same final hash as the open run"
    );
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_file(&secret_file);
}

/// A raw HTTP/2 client opens Attach and announces a 2^31-1 byte message before Hello,
/// then pushes 4 MiB: the stream is refused, the master's memory does not grow, and
/// the master still admits its worker afterwards.
#[test]
fn a_huge_message_before_hello_is_refused_without_growing_memory() {
    let out = out_dir("trust-huge");
    let (mut m, url) = master(&test_scene(SCENE), 1, &out, &["--estimated-costs"]);
    let addr = url.trim_start_matches("http://").to_string();
    let pid = m.pid();
    let (rss0, vm0) = (proc_status_kb(pid, "VmRSS"), proc_status_kb(pid, "VmSize"));
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let status = rt.block_on(async move {
        let tcp = tokio::net::TcpStream::connect(&addr).await.unwrap();
        let (client, conn) = h2::client::handshake(tcp).await.unwrap();
        tokio::spawn(async move {
            let _ = conn.await;
        });
        let mut client = client.ready().await.unwrap();
        let req = http::Request::post(format!("http://{addr}/crash.v1.Coordinator/Attach"))
            .header("content-type", "application/grpc")
            .header("te", "trailers")
            .body(())
            .unwrap();
        let (resp, mut send) = client.send_request(req, false).unwrap();
        let mut data = vec![0u8, 0x7f, 0xff, 0xff, 0xff];
        data.resize(4 << 20, 0xab);
        send.reserve_capacity(data.len());
        let _ = send.send_data(bytes::Bytes::from(data), false);
        let resp = tokio::time::timeout(Duration::from_secs(20), resp)
            .await
            .unwrap()
            .unwrap();
        let mut body = resp.into_body();
        // drain to the trailers (the refusal's grpc-status)
        let _ = tokio::time::timeout(Duration::from_secs(20), async {
            while let Some(d) = body.data().await {
                if d.is_err() {
                    break;
                }
            }
        })
        .await;
        let t = tokio::time::timeout(Duration::from_secs(5), body.trailers()).await;
        match t {
            Ok(Ok(Some(h))) => h
                .get("grpc-status")
                .map(|v| v.to_str().unwrap_or("").to_string())
                .unwrap_or_default(),
            other => format!("{other:?}"),
        }
    });
    m.expect_line("refused a connection", Duration::from_secs(10));
    let (rss1, vm1) = (proc_status_kb(pid, "VmRSS"), proc_status_kb(pid, "VmSize"));
    eprintln!("master VmRSS {rss0} -> {rss1} kB, VmSize {vm0} -> {vm1} kB; refusal: {status}");
    assert!(
        rss1 < rss0 + 32 * 1024,
        "resident memory grew: {rss0} -> {rss1} kB"
    );
    assert!(
        vm1 < vm0 + 256 * 1024,
        "address space grew: {vm0} -> {vm1} kB"
    );
    assert!(
        m.log()
            .contains("exceeds this connection's limit of 4096 bytes before the handshake"),
        "{}",
        m.log()
    );
    // the real worker still attaches and the run ends
    let mut w = worker(&url, 1, &[]);
    assert!(m.wait(RUN_TIMEOUT).success(), "{}", m.log());
    assert!(w.wait(Duration::from_secs(30)).success(), "{}", w.log());
    let _ = std::fs::remove_dir_all(&out);
}

/// A TCP connection that never says anything is closed after the handshake timeout;
/// a flood of idle connections does not keep the real worker out.
#[test]
fn an_idle_connection_is_closed_after_the_handshake_timeout() {
    let out = out_dir("trust-idle");
    let (mut m, url) = master(
        &test_scene(SCENE),
        1,
        &out,
        &["--estimated-costs", "--handshake-timeout", "1"],
    );
    let addr = url.trim_start_matches("http://");
    let mut idle = std::net::TcpStream::connect(addr).unwrap();
    idle.set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    let t0 = Instant::now();
    let mut buf = [0u8; 256];
    // the server's SETTINGS arrive first; then the connection must end
    loop {
        match idle.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(_) => {}
        }
        assert!(t0.elapsed() < Duration::from_secs(15), "still open");
    }
    let waited = t0.elapsed();
    assert!(
        waited >= Duration::from_millis(800) && waited < Duration::from_secs(5),
        "closed after {waited:?}"
    );
    // a flood of 200 idle connections (more than the 32 that may wait for a
    // handshake): the extra ones are closed at once, the rest after the timeout, and the
    // real worker attaches (it retries with backoff while the slots are full)
    let flood: Vec<std::net::TcpStream> = (0..200)
        .filter_map(|_| std::net::TcpStream::connect(addr).ok())
        .collect();
    let t1 = Instant::now();
    let mut w = worker(&url, 1, &[]);
    m.expect_line("workers attached", Duration::from_secs(30));
    eprintln!(
        "the worker attached {:?} after a flood of {} idle connections",
        t1.elapsed(),
        flood.len()
    );
    assert!(m.wait(RUN_TIMEOUT).success(), "{}", m.log());
    assert!(w.wait(Duration::from_secs(30)).success(), "{}", w.log());
    drop(flood);
    let _ = std::fs::remove_dir_all(&out);
}

/// The largest real message is one body's definition and state: measured here on a
/// sphere of scenes/bench/million-shells.toml (20 480 triangles); the limit after the
/// handshake leaves a margin of more than 8x.
#[test]
fn largest_body_message_fits_the_limit() {
    use crash_link::{BodyLoad, Command};
    use prost::Message;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/bench/million-shells.toml");
    let scene = crash_scene::load(&path).unwrap();
    let body = scene.body(0).unwrap();
    let elements = body.def.tris.len() + body.def.quads.len();
    let cmd = Command::Load {
        at: Default::default(),
        bodies: vec![BodyLoad::whole(body)],
    };
    let with_def = crash_link::wire::command_to_pb(&cmd, |_| false).encoded_len();
    let state = crash_link::wire::command_to_pb(&cmd, |_| true).encoded_len();
    eprintln!("{elements} elements: Load with definition {with_def} B, state only {state} B");
    assert!(elements == 20_480);
    assert!(with_def * 8 < crash_link::MAX_MESSAGE, "{with_def} B");
}

/// SIGTERM stops crash-master cleanly: the current step finishes, then a checkpoint,
/// the last frame, summary.json marked interrupted; the workers are told to stop
/// (exit 0); the master exits with 130.
#[test]
fn sigterm_stops_the_master_cleanly() {
    let out = out_dir("trust-sigterm");
    let (mut m, url) = master(
        &test_scene("ten-spheres-tiny.toml"),
        1,
        &out,
        &["--estimated-costs", "--end-time", "1.0"],
    );
    let mut w = worker(&url, 1, &[]);
    m.expect_line("workers attached", Duration::from_secs(30));
    std::thread::sleep(Duration::from_millis(1500));
    m.signal("TERM");
    let status = m.wait(Duration::from_secs(60));
    assert_eq!(status.code(), Some(130), "{}", m.log());
    assert!(w.wait(Duration::from_secs(30)).success(), "{}", w.log());
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    let fault = s.fault.clone().unwrap_or_default();
    assert!(fault.contains("interrupted at step"), "{fault}");
    assert!(s.interrupted);
    assert!(s.steps > 0 && s.time_reached_s < 1.0, "{} steps", s.steps);
    assert!(
        s.final_state_hash.len() == 16 && s.final_state_hash != format!("{:016x}", 0),
        "the last frame's hash: {:?}",
        s.final_state_hash
    );
    let ckp = crash_master::read_restart(&out.join(crash_master::RESTART_FILE)).unwrap();
    assert_eq!(
        ckp.master.clock.step, s.steps,
        "checkpoint at the last step"
    );
    let _ = std::fs::remove_dir_all(&out);
}
