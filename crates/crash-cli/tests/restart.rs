//! `crash run --checkpoint-every N` and `crash run --restart FILE`: a run interrupted
//! after a checkpoint and restarted ends with exactly the files of an uninterrupted run.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const CRASH: &str = env!("CARGO_BIN_EXE_crash");

/// Two steel spherical shells meeting head-on (contact, MEIM merge and split); the
/// output interval is explicit so a shortened end time keeps the frame schedule.
const SCENE: &str = r#"
name = "restart-two-spheres"
end_time = 3.4e-3
output_interval = 5.0e-4

[contact]
penalty = "soft"
penalty_scale = 0.1

[materials.steel]
density = 7800.0
young = 200.0e9
poisson = 0.3

[[bodies]]
name = "left"
material = "steel"
thickness = 1.0e-3
sphere = { radius = 0.05, level = 2 }
position = [-0.0625, 0.0, 0.0]
velocity = [5.0, 0.0, 0.0]

[[bodies]]
name = "right"
material = "steel"
thickness = 1.0e-3
sphere = { radius = 0.05, level = 2 }
position = [0.0625, 0.0, 0.0]
velocity = [VR, 0.0, 0.0]
"#;

fn workdir(name: &str) -> PathBuf {
    // per process: the target directory (and its tmp) is shared by concurrent runs
    let d =
        PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn scene(dir: &Path, right_velocity: &str) -> PathBuf {
    let p = dir.join(format!("scene{right_velocity}.toml"));
    std::fs::write(&p, SCENE.replace("VR", right_velocity)).unwrap();
    p
}

fn crash(args: &[&str]) -> Output {
    let mut all = vec!["run", "--quiet", "--no-pictures", "--workers", "2"];
    all.extend_from_slice(args);
    Command::new(CRASH).args(&all).output().unwrap()
}

fn ok(o: Output) -> Output {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// energy.csv, contacts.csv, frames.pvd, the last frame's data and the summary's step
/// count, time, dt range and final state hash of run `b` equal those of run `a`.
fn assert_same_run(a: &Path, b: &Path) {
    for f in ["energy.csv", "contacts.csv", "frames.pvd"] {
        assert!(read(&a.join(f)) == read(&b.join(f)), "{f} differs");
    }
    let rows = read(&a.join("contacts.csv")).split(|&c| c == b'\n').count();
    assert!(rows > 10, "the spheres should touch: {rows} contact rows");
    let frames = crash_io::read_pvd(&a.join("frames.pvd")).unwrap();
    assert_eq!(frames.len(), 8, "frames at 0, 0.5, ..., 3.0 ms and 3.4 ms");
    let last = &frames[frames.len() - 1].file;
    // the frames' physical data (read back: every bit); the `worker` cell field shows
    // the placement, which measured costs make differ from run to run
    let physical = |p: &Path| {
        let mut f = crash_io::read_vtu(p).unwrap();
        for b in &mut f.bodies {
            (b.placement, b.parts) = (None, None);
        }
        f
    };
    let (fa, fb) = (physical(&a.join(last)), physical(&b.join(last)));
    assert!(fa == fb, "{last} differs");
    let (sa, sb) = (
        crash_io::read_summary(a.join("summary.json")).unwrap(),
        crash_io::read_summary(b.join("summary.json")).unwrap(),
    );
    assert!(!sa.final_state_hash.is_empty());
    assert_eq!(sa.final_state_hash, sb.final_state_hash);
    assert_eq!(sa.steps, sb.steps);
    assert_eq!(sa.time_reached_s.to_bits(), sb.time_reached_s.to_bits());
    assert_eq!(sa.dt_min_s.to_bits(), sb.dt_min_s.to_bits());
    assert_eq!(sa.dt_max_s.to_bits(), sb.dt_max_s.to_bits());
    assert_eq!(
        sa.energy_balance_error.to_bits(),
        sb.energy_balance_error.to_bits()
    );
    assert_eq!(sa.indicators, sb.indicators);
}

#[test]
fn interrupted_and_restarted_run_equals_the_uninterrupted_run() {
    let d = workdir("cli-restart");
    let sc = scene(&d, "-5.0");
    let (a, b, c) = (d.join("a"), d.join("b"), d.join("c"));
    ok(crash(&[s(&sc), "--out", s(&a)]));

    // b: stopped early (a shorter end time: its last, shortened step and final frame
    // come after the last checkpoint and must be replaced), then restarted
    ok(crash(&[
        s(&sc),
        "--out",
        s(&b),
        "--end-time",
        "1.7e-3",
        "--checkpoint-every",
        "100",
    ]));
    let ckp = b.join("restart.ckp");
    let r = crash_master::read_restart(&ckp).unwrap();
    assert!(
        r.master.clock.step >= 100 && r.master.clock.time < 1.7e-3,
        "{}",
        r.master.clock.step
    );
    let o = ok(crash(&[
        s(&sc),
        "--restart",
        s(&ckp),
        "--checkpoint-every",
        "100",
    ]));
    assert!(String::from_utf8_lossy(&o.stderr).contains("restarting from"));
    assert_same_run(&a, &b);

    // c: a complete run restarted from its last checkpoint redoes the end identically
    ok(crash(&[
        s(&sc),
        "--out",
        s(&c),
        "--checkpoint-every",
        "150",
    ]));
    let ckp = c.join("restart.ckp");
    let step = crash_master::read_restart(&ckp).unwrap().master.clock.step;
    ok(crash(&[s(&sc), "--restart", s(&ckp), "--out", s(&c)]));
    assert_same_run(&a, &c);
    assert!(step >= 150);
}

#[test]
fn corrupt_or_foreign_checkpoints_are_refused_with_the_file_named() {
    let d = workdir("cli-restart-bad");
    let sc = scene(&d, "-5.0");
    let out = d.join("run");
    ok(crash(&[
        s(&sc),
        "--out",
        s(&out),
        "--end-time",
        "5e-4",
        "--checkpoint-every",
        "20",
    ]));
    let ckp = out.join("restart.ckp");
    let good = read(&ckp);

    let refused = |file: &Path, scene_file: &Path, what: &str| {
        let o = crash(&[s(scene_file), "--restart", s(file)]);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(s(file)) && err.contains(what), "{err}");
    };
    // a flipped payload byte
    let mut bad = good.clone();
    let n = bad.len();
    bad[n - 100] ^= 0x10;
    let corrupt = d.join("corrupt.ckp");
    std::fs::write(&corrupt, &bad).unwrap();
    refused(&corrupt, &sc, "corrupt (checksum mismatch)");
    // cut short
    let short = d.join("short.ckp");
    std::fs::write(&short, &good[..n / 2]).unwrap();
    refused(&short, &sc, "truncated");
    // not a checkpoint
    let text = d.join("text.ckp");
    std::fs::write(&text, b"time,kinetic\n").unwrap();
    refused(&text, &sc, "not a crash checkpoint");
    // a different scene (the right sphere slower)
    refused(&ckp, &scene(&d, "-4.0"), "another scene");
    // the run directory was left alone by the refusals
    assert!(read(&ckp) == good);
}
