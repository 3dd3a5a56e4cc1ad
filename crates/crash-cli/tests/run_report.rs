//! What `crash run` tells: exit codes (docs/output.md), warnings on the console once and
//! in summary.json, a complete summary after a fault, and a shortened last step that
//! distorts no figure.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("test dir");
    d
}

/// A thin sphere (R/t = 200, level 3) thrown at `speed` onto a clamped plate.
fn fast_scene(d: &Path, speed: f64, rule: &str, extra: &str) -> PathBuf {
    let t = 2.5e-4;
    let z = 0.05 + 0.5 * (t + 1e-3) + 1e-3;
    let text = format!(
        r#"name = "fast"
end_time = {end}
output_interval = {end}
{extra}
[contact]
speed_rule = "{rule}"
[materials.steel]
density = 7800.0
young = 200.0e9
poisson = 0.3
[[bodies]]
name = "plate"
material = "steel"
thickness = 1.0e-3
plate = {{ size = [0.2, 0.2], cells = [20, 20] }}
[[bodies.fix]]
select = ["x-", "x+", "y-", "y+"]
dofs = "all"
[[bodies]]
name = "sphere"
material = "steel"
thickness = {t}
sphere = {{ radius = 0.05, level = 3 }}
position = [0.0, 0.0, {z}]
velocity = [0.0, 0.0, -{speed}]
"#,
        end = 0.12 / speed
    );
    let p = d.join("scene.toml");
    std::fs::write(&p, text).expect("scene");
    p
}

fn crash(scene: &Path, out: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_crash"))
        .arg("run")
        .arg(scene)
        .args(["--quiet", "--no-pictures", "--threads", "2", "--out"])
        .arg(out)
        .args(args)
        .output()
        .expect("crash runs")
}

#[test]
fn pass_through_exits_3_with_a_complete_summary_naming_both_bodies() {
    let d = dir("report-pass-through");
    let sc = fast_scene(&d, 2000.0, "stop", "");
    let out = d.join("out");
    let o = crash(&sc, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{err}");
    assert_eq!(o.status.code(), Some(3), "{err}");
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).expect("summary");
    let fault = s.fault.expect("the fault is in summary.json");
    assert!(fault.contains("passed through"), "{fault}");
    assert!(
        fault.contains("'plate'") && fault.contains("'sphere'"),
        "{fault}"
    );
    assert!(fault.contains("m/s"), "closing speed: {fault}");
    // steps done and time reached, not zeros
    assert!(s.steps >= 1, "steps {}", s.steps);
    assert!(s.time_reached_s > 0.0 && s.dt_min_s > 0.0);
    assert!(s.final_state_hash.is_empty());
    assert!(err.contains(&format!("{} steps done", s.steps)), "{err}");
}

/// The energy warning's lines on stderr.
fn energy_warnings(err: &str) -> Vec<&str> {
    err.lines()
        .filter(|l| l.contains("crash: warning:") && l.contains("energy-balance error"))
        .collect()
}

/// A scene whose `energy_limit` no run can meet, run to `end` seconds.
fn impossible_limit_scene(d: &Path, end: &str) -> PathBuf {
    let sc = fast_scene(d, 2.0, "limit_dt", "energy_limit = 1.0e-15");
    let sc_text = std::fs::read_to_string(&sc).expect("scene");
    std::fs::write(
        &sc,
        sc_text.replace("end_time = 0.06", &format!("end_time = {end}")),
    )
    .expect("scene");
    sc
}

#[test]
fn a_doubtful_warning_is_printed_once_listed_and_exits_4_unless_allowed() {
    let d = dir("report-warning");
    // past the limit from the first step, but the run ends (3 records) before the
    // energy guard's persistence (more than 3 steps) stops it: it finishes warned
    let sc = impossible_limit_scene(&d, "2.0e-6");
    let out = d.join("out");
    let o = crash(&sc, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{err}");
    assert_eq!(o.status.code(), Some(4), "{err}");
    let lines = energy_warnings(&err);
    assert_eq!(lines.len(), 1, "printed once: {lines:?}");
    assert!(
        lines[0].contains("step ") && lines[0].contains("t = "),
        "{}",
        lines[0]
    );
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).expect("summary");
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert_eq!(s.warnings[0].kind, crash_io::WarningKind::EnergyBalance);
    assert!(s.warnings[0].doubtful);
    assert_eq!(s.energy_limit, 1e-15);
    assert!(s.fault.is_none());

    let o = crash(&sc, &d.join("allowed"), &["--allow-warnings"]);
    assert_eq!(o.status.code(), Some(0));
}

/// One energy limit: the figure the warning judges is the figure the guard judges, so a
/// run past `energy_limit` for more than 3 steps is stopped (exit 3) after the warning.
#[test]
fn an_energy_error_past_the_limit_warns_once_then_the_guard_stops_the_run_with_exit_3() {
    let d = dir("report-energy-guard");
    let sc = impossible_limit_scene(&d, "1.0e-5");
    let out = d.join("out");
    let o = crash(&sc, &out, &["--allow-warnings"]);
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{err}");
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert_eq!(energy_warnings(&err).len(), 1, "{err}");
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).expect("summary");
    let fault = s.fault.expect("the guard's fault is in summary.json");
    assert!(
        fault.contains("energy runaway") && fault.contains("energy_limit"),
        "{fault}"
    );
    assert_eq!(s.steps, 4, "stopped on the 4th step past the limit");
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert_eq!(s.warnings[0].kind, crash_io::WarningKind::EnergyBalance);
}

#[test]
fn shortened_last_step_enters_neither_dt_min_nor_the_energy_figure() {
    let d = dir("report-short-step");
    let sc = fast_scene(&d, 2.0, "limit_dt", "");
    // a full run of 40 steps, then the same run with a sliver of a 41st step
    let o = crash(&sc, &d.join("probe"), &["--end-time", "1e-5"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let probe =
        crash_io::read_summary(d.join("probe").join(crash_io::SUMMARY_JSON)).expect("summary");
    let dt = probe.dt_max_s;
    let full = 40.0 * dt;
    let run = |name: &str, end: f64| {
        let o = crash(&sc, &d.join(name), &["--end-time", &format!("{end:e}")]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        crash_io::read_summary(d.join(name).join(crash_io::SUMMARY_JSON)).expect("summary")
    };
    let a = run("full", full * (1.0 - 1e-13));
    let b = run("sliver", full + 1e-4 * dt);
    println!(
        "full: {} steps, dt {:e}..{:e}, error {:e}; sliver: {} steps, last {:e}, dt {:e}..{:e}, error {:e}",
        a.steps, a.dt_min_s, a.dt_max_s, a.energy_balance_error,
        b.steps, b.last_dt_s, b.dt_min_s, b.dt_max_s, b.energy_balance_error
    );
    assert_eq!(b.steps, a.steps + 1);
    assert!(b.last_dt_s > 0.0 && b.last_dt_s < 1e-3 * dt);
    assert_eq!(b.dt_min_s, a.dt_min_s);
    assert_eq!(b.energy_balance_error, a.energy_balance_error);
}

#[test]
fn two_plates_with_a_1e4_density_ratio_draw_no_contact_energy_warning() {
    let d = dir("report-two-plates");
    let sc = d.join("scene.toml");
    std::fs::write(
        &sc,
        r#"name = "two-plates"
end_time = 4.0e-4
output_interval = 1.0e-4
[materials.steel]
density = 7800.0
young = 200.0e9
poisson = 0.3
[materials.heavy]
density = 7.8e7
young = 200.0e9
poisson = 0.3
[[bodies]]
name = "light"
material = "steel"
thickness = 1.0e-3
plate = { size = [0.05, 0.05], cells = [5, 5] }
[[bodies]]
name = "heavy"
material = "heavy"
thickness = 1.0e-3
plate = { size = [0.05, 0.05], cells = [5, 5] }
position = [0.0, 0.0, 1.1e-3]
velocity = [0.0, 0.0, -1.0]
"#,
    )
    .expect("scene");
    let out = d.join("out");
    let o = crash(&sc, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).expect("summary");
    let ind = s.indicators;
    println!(
        "contact flow {:.3e} J, peak internal {:.3e} J, made by contact {:.3e}",
        ind.contact_flow_j, ind.peak_internal_j, ind.contact_generated_ratio
    );
    // the contact stores far more than the plates' internal energy (the old rule,
    // |E_c| against the peak internal energy, fired here) and makes none
    assert!(ind.contact_flow_j > 10.0 * ind.peak_internal_j);
    assert!(ind.contact_generated_ratio < 0.01);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}
