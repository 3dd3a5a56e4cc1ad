//! `crash run` as a person runs it: its console output in a log, Ctrl-C (SIGINT) and
//! the restart after it, a full disk, and input that must not reach the file system.
#![allow(clippy::unwrap_used)]

use crash_tests::fixtures::test_scene;
use crash_tests::procs::{bin, out_dir, Proc};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const LONG: Duration = Duration::from_secs(600);

/// Frames every 0.1 ms of the 3.4 ms run: 35 frames, so "the first frames appear" is
/// long before the end.
fn two_spheres(out: &Path, extra: &[&str]) -> Vec<String> {
    let mut a: Vec<String> = [
        "run",
        test_scene("two-spheres-tiny.toml").to_str().unwrap(),
        "--output-interval",
        "1e-4",
        "--threads",
        "1",
        "--no-pictures",
        "--out",
        out.to_str().unwrap(),
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    a.extend(extra.iter().map(|s| s.to_string()));
    a
}

fn crash(args: &[String]) -> Proc {
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    Proc::spawn("crash", &bin("crash"), &a)
}

/// Run to the end; exit code and stderr.
fn crash_done(args: &[String]) -> (Option<i32>, String) {
    let mut p = crash(args);
    let status = p.wait(LONG);
    (status.code(), p.log())
}

fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                todo.push(p);
            } else {
                out.push(p);
            }
        }
    }
    out
}

fn tmp_files(dir: &Path) -> Vec<PathBuf> {
    files_under(dir)
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "tmp"))
        .collect()
}

fn vtu_count(out: &Path) -> usize {
    files_under(&out.join(crash_io::series::FRAMES_DIR))
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "vtu"))
        .count()
}

/// stderr not a terminal (a pipe, as in CI or `2> log`): plain lines, no progress bar,
/// no colour: not one ESC byte, whatever is printed (notes, progress, log lines, the
/// final line).
#[test]
fn crash_run_with_stderr_piped_writes_no_escape_codes() {
    let out = out_dir("console-plain");
    let (code, log) = crash_done(&two_spheres(&out, &[]));
    assert_eq!(code, Some(0), "{log}");
    assert!(!log.contains('\x1b'), "escape code in the log:\n{log:?}");
    assert!(log.contains("crash: t = "), "a plain progress line:\n{log}");
    assert!(log.contains("crash: done:"), "{log}");
    let _ = std::fs::remove_dir_all(&out);
}

/// SIGINT while frames are being written: the step in progress completes, then the
/// last frame, restart.ckp and summary.json marked interrupted; exit 130. A restart
/// with an end time before the checkpoint is refused and leaves the directory as it
/// was; `--restart` then ends with exactly the uninterrupted run's final state hash
/// and step count.
#[test]
fn sigint_stops_crash_run_cleanly_and_the_restart_matches_the_uninterrupted_run() {
    let full = out_dir("console-full");
    let (code, log) = crash_done(&two_spheres(&full, &["--quiet"]));
    assert_eq!(code, Some(0), "{log}");
    let reference = crash_io::read_summary(full.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(!reference.interrupted);

    let out = out_dir("console-sigint");
    let mut p = crash(&two_spheres(&out, &["--quiet"]));
    // the first frames: then stop the process, queue SIGINT and let it go on, so the
    // signal is handled with the run in the middle whatever the machine's load
    let end = Instant::now() + LONG;
    while vtu_count(&out) < 3 {
        assert!(Instant::now() < end, "no frames: {}", p.log());
        std::thread::sleep(Duration::from_millis(5));
    }
    p.signal("STOP");
    p.signal("INT");
    p.signal("CONT");
    let status = p.wait(LONG);
    let log = p.log();
    assert_eq!(status.code(), Some(130), "{log}");
    assert!(log.contains("--restart"), "says how to continue:\n{log}");

    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(s.interrupted, "{s:?}");
    assert!(
        s.fault
            .as_deref()
            .unwrap_or("")
            .contains("interrupted at step"),
        "{:?}",
        s.fault
    );
    assert!(
        s.steps > 0 && s.steps < reference.steps,
        "{} of {} steps",
        s.steps,
        reference.steps
    );
    assert_eq!(s.final_state_hash.len(), 16, "{s:?}");
    let ckp = crash_master::read_restart(&out.join(crash_master::RESTART_FILE)).unwrap();
    assert_eq!(
        ckp.master.clock.step, s.steps,
        "checkpoint at the last step"
    );
    // the last frame is that step's, complete and readable
    let pvd = crash_io::read_pvd(&out.join(crash_io::PVD_FILE)).unwrap();
    let last = crash_io::read_vtu(&out.join(&pvd.last().unwrap().file)).unwrap();
    assert_eq!(last.step, s.steps);
    assert_eq!(last.bodies.len(), 2);
    assert!(tmp_files(&out).is_empty(), "{:?}", tmp_files(&out));

    let ckp_path = out.join(crash_master::RESTART_FILE);
    let restart = |extra: &[&str]| {
        let mut a = two_spheres(&out, &["--quiet", "--restart", ckp_path.to_str().unwrap()]);
        a.extend(extra.iter().map(|s| s.to_string()));
        crash_done(&a)
    };
    // an end time before the checkpoint: refused before the directory is touched
    let energy = std::fs::read(out.join(crash_io::ENERGY_CSV)).unwrap();
    let (code, log) = restart(&["--end-time", "1e-5"]);
    assert_eq!(code, Some(2), "{log}");
    assert!(
        log.contains("is before the checkpoint's time") && log.contains("restart.ckp"),
        "{log}"
    );
    assert_eq!(
        std::fs::read(out.join(crash_io::ENERGY_CSV)).unwrap(),
        energy
    );

    let (code, log) = restart(&[]);
    assert_eq!(code, Some(0), "{log}");
    let r = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(!r.interrupted && r.fault.is_none(), "{r:?}");
    assert_eq!(r.final_state_hash, reference.final_state_hash);
    assert_eq!(r.steps, reference.steps);
    // the series and the histories are the uninterrupted run's (the stop's extra
    // frame is dropped at the restart)
    for f in [
        crash_io::PVD_FILE,
        crash_io::ENERGY_CSV,
        crash_io::CONTACTS_CSV,
    ] {
        let a = std::fs::read(full.join(f)).unwrap();
        let b = std::fs::read(out.join(f)).unwrap();
        assert!(a == b, "{f} differs from the uninterrupted run's");
    }
    assert_eq!(vtu_count(&out), vtu_count(&full));
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&full);
}

/// A tmpfs mounted for the test, unmounted on drop (needs root: CAP_SYS_ADMIN).
struct Tmpfs(PathBuf);

impl Tmpfs {
    fn mount(dir: PathBuf, size: &str) -> Option<Self> {
        std::fs::create_dir_all(&dir).unwrap();
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(&dir)
            .stderr(std::process::Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        ok.then_some(Self(dir))
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

/// The run directory on a 256 KiB file system: the frames fill it, the run stops with
/// exit 1 naming the file it could not write, and no temporary file is left behind
/// (without root the unit tests of crash_io::atomic show the same with an injected
/// write error).
#[test]
fn a_full_disk_stops_the_run_with_exit_1_and_leaves_no_temporary_files() {
    let base = out_dir("console-full-disk");
    let Some(fs) = Tmpfs::mount(base.join("mnt"), "256k") else {
        eprintln!("SKIP: cannot mount a tmpfs here (not root); crash_io::atomic's unit tests cover the write error");
        return;
    };
    let out = fs.0.join("run");
    let (code, log) = crash_done(&two_spheres(&out, &["--quiet"]));
    assert_eq!(code, Some(1), "{log}");
    assert!(
        log.contains("No space left on device") || log.contains("os error 28"),
        "{log}"
    );
    assert!(tmp_files(&fs.0).is_empty(), "{:?}", tmp_files(&fs.0));
    drop(fs);
    let _ = std::fs::remove_dir_all(&base);
}

/// A scene whose name is a path is refused (exit 2) with the file, line and key
/// named, before anything is written.
#[test]
fn a_scene_name_that_is_a_path_is_refused_by_crash_run() {
    let dir = out_dir("console-name");
    let text = std::fs::read_to_string(test_scene("two-spheres-tiny.toml")).unwrap();
    let text = text.replace("name = \"two-spheres-tiny\"", "name = \"../../escaped\"");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let args: Vec<String> = ["run", scene.to_str().unwrap(), "--no-pictures"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let (code, log) = crash_done(&args);
    assert_eq!(code, Some(2), "{log}");
    assert!(
        log.contains("scene.toml:") && log.contains("name = \"../../escaped\""),
        "{log}"
    );
    assert!(log.contains("one plain file name"), "{log}");
    let _ = std::fs::remove_dir_all(&dir);
}
