//! Issue 14, hardening (docs/reliability.md), on loopback processes: a worker that
//! holds the secret but reports what cannot be true (a negative kinetic energy, a fault
//! of a body it does not hold, a made-up fault of its own body that a replay on the
//! other worker does not confirm) is dropped and the run ends on the honest worker with
//! the fault-free hash; a real fault is confirmed by the replay and ends the run as
//! `crash run` does; TLS gives the plain run's hash and refuses a worker that trusts
//! another certificate; an edited keyed restart file is refused naming it. Every wait is
//! bounded; children are killed on drop.
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

/// The run without fault on two workers (once per test binary).
fn reference_hash() -> String {
    static H: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    H.get_or_init(|| {
        let out = out_dir("hardening-reference");
        let (mut m, url) = master(&test_scene(SCENE), 2, &out, &["--end-time", END_TIME]);
        let _w: Vec<_> = (0..2).map(|_| worker(&url, 1, &[])).collect();
        assert!(m.wait(TIMEOUT).success(), "{}", m.log());
        let h = final_hash(&out);
        let _ = std::fs::remove_dir_all(&out);
        h
    })
    .clone()
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

/// Step reports seen by the worker that makes up a fault.
static FAULT_REPORTS: AtomicU64 = AtomicU64::new(0);

/// Honest for 300 reports, then a fault of a body that is not in the run.
fn made_up_fault(reply: &mut Reply) {
    if matches!(reply, Reply::Report(_)) && FAULT_REPORTS.fetch_add(1, Ordering::Relaxed) == 300 {
        *reply = Reply::Fault {
            group_first: 9999,
            fault: crash_core::Fault::NonFinite {
                step: 1,
                body: 9999,
                place: "node 0".into(),
                what: "velocity or position",
            },
            split_contacts: None,
        };
    }
}

/// Step reports seen by the worker that makes up a fault of its own body.
static OWN_FAULT_REPORTS: AtomicU64 = AtomicU64::new(0);

/// Honest for 300 reports, then a fault of the first body it holds (a body and group it
/// does hold: the plausibility checks pass it).
fn made_up_own_fault(reply: &mut Reply) {
    let Reply::Report(rep) = reply else { return };
    let Some(first) = rep.bodies.first().map(|b| b.id) else {
        return;
    };
    if OWN_FAULT_REPORTS.fetch_add(1, Ordering::Relaxed) == 300 {
        *reply = Reply::Fault {
            group_first: first,
            fault: crash_core::Fault::NonFinite {
                step: 301,
                body: first,
                place: "node 0".into(),
                what: "velocity or position",
            },
            split_contacts: None,
        };
    }
}

/// A run of the scene on an honest worker process and a lying one in this process
/// (both with the secret); the master's log once it succeeded.
fn run_with_a_liar(tag: &str, tamper: fn(&mut Reply)) -> String {
    let expected = reference_hash();
    let out = out_dir(tag);
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
    opts.tamper = Some(tamper);
    let liar = std::thread::spawn(move || crash_worker::run(&opts));
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    let log = m.log();
    assert!(log.contains("continuing from step"), "{log}");
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
    log
}

#[test]
fn a_worker_reporting_negative_kinetic_energy_is_dropped_and_the_run_ends_with_the_fault_free_hash()
{
    let log = run_with_a_liar("hardening-liar", lie);
    assert!(
        log.contains("reported what cannot be true: body")
            && log.contains("negative kinetic energy -1e0"),
        "{log}"
    );
    assert!(
        REPORTS.load(Ordering::Relaxed) > 300,
        "the lie was never told"
    );
}

#[test]
fn a_worker_making_up_a_fault_of_a_body_it_does_not_hold_is_dropped_not_believed() {
    let log = run_with_a_liar("hardening-fault", made_up_fault);
    assert!(
        log.contains("reported what cannot be true: a fault naming body 9999"),
        "{log}"
    );
    assert!(FAULT_REPORTS.load(Ordering::Relaxed) > 300);
}

#[test]
fn a_worker_making_up_a_fault_of_its_own_body_is_dropped_and_the_run_ends_with_the_fault_free_hash()
{
    let log = run_with_a_liar("hardening-own-fault", made_up_own_fault);
    assert!(
        log.contains("reported a fault: step 301: non-finite velocity or position")
            && log.contains("replays it on the other workers"),
        "{log}"
    );
    assert!(
        log.contains("reported what cannot be true: a fault that did not recur when its step was replayed on the other workers"),
        "{log}"
    );
    assert!(OWN_FAULT_REPORTS.load(Ordering::Relaxed) > 300);
}

#[test]
fn a_real_fault_in_a_cluster_run_is_confirmed_by_the_replay_and_ends_with_exit_3_as_crash_run() {
    // two spheres closing at 400 m/s with a tiny contact margin: a tunnelling fault
    let out = out_dir("hardening-real-fault");
    std::fs::create_dir_all(&out).unwrap();
    let text = std::fs::read_to_string(test_scene("two-spheres-tiny.toml"))
        .unwrap()
        .replace(
            "penalty_scale = 0.1",
            "penalty_scale = 0.1\nmargin = 1.0e-5",
        )
        .replace("velocity = [5.0, 0.0, 0.0]", "velocity = [400.0, 0.0, 0.0]");
    let scene = out.join("fast.toml");
    std::fs::write(&scene, &text).unwrap();
    let local = out.join("local");
    let (s, l) = (scene.to_str().unwrap(), local.to_str().unwrap());
    let mut p = crash_tests::procs::Proc::spawn(
        "crash",
        &crash_tests::procs::bin("crash"),
        &["run", s, "--out", l, "--quiet", "--no-pictures"],
    );
    assert_eq!(p.wait(TIMEOUT).code(), Some(3), "{}", p.log());
    let expected = crash_io::read_summary(local.join(crash_io::SUMMARY_JSON))
        .unwrap()
        .fault
        .unwrap();
    // 2 workers, checkpoints every 20 steps: the fault is replayed, then believed
    let run = out.join("cluster");
    let (mut m, url) = master(
        &scene,
        2,
        &run,
        &["--checkpoint-seconds", "0", "--checkpoint-every", "20"],
    );
    let mut w: Vec<_> = (0..2).map(|_| worker(&url, 1, &[])).collect();
    assert_eq!(m.wait(TIMEOUT).code(), Some(3), "{}", m.log());
    let log = m.log();
    assert!(log.contains("replays it on the other workers"), "{log}");
    assert!(log.contains("in the replay: it is real"), "{log}");
    assert!(log.contains(&expected), "expected '{expected}':\n{log}");
    let s = crash_io::read_summary(run.join(crash_io::SUMMARY_JSON)).unwrap();
    assert_eq!(s.fault.as_deref(), Some(expected.as_str()));
    // both workers (the one set aside too) were told to stop
    for p in &mut w {
        assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// `crash run` with these arguments and environment; (success, stderr).
fn crash_run(args: &[&str], env: &[(&str, &str)]) -> (bool, String) {
    let mut p =
        crash_tests::procs::Proc::spawn_env("crash", &crash_tests::procs::bin("crash"), args, env);
    let ok = p.wait(TIMEOUT).success();
    (ok, p.log())
}

#[test]
fn an_edited_keyed_restart_file_is_refused_naming_it_and_a_keyed_one_needs_the_secret() {
    let out = out_dir("hardening-keyed");
    let scene = test_scene("two-spheres-tiny.toml");
    let (scene, dir) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let key = [("CRASH_SECRET", SECRET)];
    let base = ["run", scene, "--out", dir, "--quiet", "--no-pictures"];
    let mut first = base.to_vec();
    first.extend(["--end-time", "0.0004", "--checkpoint-every", "50"]);
    let (ok, log) = crash_run(&first, &key);
    assert!(ok, "{log}");
    let ckp = out.join(crash_master::RESTART_FILE);
    let good = std::fs::read(&ckp).unwrap();
    assert_eq!(
        &good[..8],
        b"CRASHCKM",
        "a secret is set: the restart file is keyed"
    );
    let ckp_s = ckp.to_str().unwrap();
    let mut again = base.to_vec();
    again.extend(["--end-time", "0.0006", "--restart", ckp_s]);

    // without the secret: refused, saying it is keyed
    let (ok, log) = crash_run(&again, &[]);
    assert!(
        !ok && log.contains("restart.ckp") && log.contains("is keyed"),
        "{log}"
    );

    // one byte of the payload edited, its plain checksum recomputed: refused by the MAC
    let header = 8 + 4 + 8 + 8 + 32;
    let mut bad = good.clone();
    let k = header + (bad.len() - header) / 3;
    bad[k] ^= 0x10;
    let mut h = crash_core::hash::Fnv::default();
    h.bytes(&bad[header..]);
    bad[20..28].copy_from_slice(&h.finish().to_le_bytes());
    std::fs::write(&ckp, &bad).unwrap();
    let (ok, log) = crash_run(&again, &key);
    assert!(
        !ok && log.contains(ckp_s)
            && log.contains("was edited or written under another shared secret"),
        "{log}"
    );

    // the file as written continues with the secret
    std::fs::write(&ckp, &good).unwrap();
    let (ok, log) = crash_run(&again, &key);
    assert!(ok, "{log}");
    let _ = std::fs::remove_dir_all(&out);
}

/// `crash-master cert --out DIR --host 127.0.0.1 --host localhost`; the pair's paths.
fn make_cert(dir: &Path) -> (String, String) {
    let mut p = crash_tests::procs::Proc::spawn(
        "crash-master cert",
        &crash_tests::procs::master_bin(),
        &[
            "cert",
            "--out",
            dir.to_str().unwrap(),
            "--host",
            "127.0.0.1",
            "--host",
            "localhost",
        ],
    );
    assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    let s = |f: &str| dir.join(f).to_str().unwrap().to_string();
    (s("cert.pem"), s("key.pem"))
}

#[test]
fn a_tls_run_gives_the_plain_hash_and_a_worker_trusting_another_ca_is_refused() {
    let scene = test_scene("two-spheres-tiny.toml");
    // plain
    let plain = out_dir("hardening-plain");
    let (mut m, url) = master(&scene, 1, &plain, &["--estimated-costs"]);
    let mut w = worker(&url, 1, &[]);
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    assert!(w.wait(Duration::from_secs(30)).success(), "{}", w.log());
    let expected = final_hash(&plain);

    let out = out_dir("hardening-tls");
    let (cert, key) = make_cert(&out.join("pki"));
    let (other, _) = make_cert(&out.join("other-pki"));
    let (mut m, url) = master(
        &scene,
        1,
        &out.join("run"),
        &["--estimated-costs", "--tls-cert", &cert, "--tls-key", &key],
    );
    let url = url.replacen("http://", "https://", 1);
    // trusts another certificate: refused at the TLS handshake, at once, saying why
    let mut wrong = worker(&url, 1, &["--tls-ca", &other]);
    assert!(!wrong.wait(Duration::from_secs(30)).success());
    assert!(
        wrong.log().contains("TLS with the master at")
            && wrong
                .log()
                .contains("must be signed by the --tls-ca certificate"),
        "{}",
        wrong.log()
    );
    // plain text to a TLS master: no session either
    let mut clear = worker(
        &url.replacen("https://", "http://", 1),
        1,
        &["--connect-timeout", "2"],
    );
    assert!(!clear.wait(Duration::from_secs(30)).success());
    // the health probe over TLS
    let mut probe = crash_tests::procs::Proc::spawn(
        "crash-worker --probe",
        &crash_tests::procs::worker_bin(),
        &["--probe", &url, "--tls-ca", &cert],
    );
    assert!(
        probe.wait(Duration::from_secs(30)).success(),
        "{}",
        probe.log()
    );
    // the right CA: the run, to the plain run's hash
    let mut w = worker(&url, 1, &["--tls-ca", &cert]);
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    assert!(w.wait(Duration::from_secs(30)).success(), "{}", w.log());
    assert_eq!(final_hash(&out.join("run")), expected);
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&plain);
}
