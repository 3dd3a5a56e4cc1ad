//! The result files an analyst reads (matsum.csv, rcforc.csv, nodout.csv, spcforc.csv)
//! from a keyword deck with *DEFINE_CURVE, *LOAD_NODE_POINT, *BOUNDARY_PRESCRIBED_MOTION
//! and *DATABASE_HISTORY_NODE: the same bytes in every mode, per-body energies that
//! add up to energy.csv, and a prescribed node that moves by its curve's integral.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_tests::fixtures::root;
use crash_tests::procs::{bin, master, out_dir, worker, Proc};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;

const TIMEOUT: Duration = Duration::from_secs(300);
const FILES: [&str; 4] = ["matsum.csv", "rcforc.csv", "nodout.csv", "spcforc.csv"];
/// The impactor's velocity scale (SF of its prescribed motion) [m/s].
const SF: f64 = -30.0;
/// The impactor's velocity curve: rises to 1 at 10 us, falls to 0.2 at 60 us, holds.
const CURVE: [(f64, f64); 3] = [(0.0, 0.0), (1e-5, 1.0), (6e-5, 0.2)];
const END: f64 = 1e-4;

/// The keyword test deck of crash-scene, changed: the impactor 2.5 mm above the plate
/// driven by a curve that rises and falls, the nodal load on a triangular pulse.
fn deck(dir: &Path) -> PathBuf {
    let src = root().join("crates/crash-scene/tests/data/keyword");
    let main = std::fs::read_to_string(src.join("impact.k")).unwrap();
    let mesh = std::fs::read_to_string(src.join("impact-mesh.k")).unwrap();
    let swap = |text: &str, from: &str, to: &str| {
        assert!(text.contains(from), "the deck has no {from:?}");
        text.replace(from, to)
    };
    let mesh = swap(
        &mesh,
        "            0.01       0",
        "          0.0025       0",
    );
    // a smaller step: the curve's kinks and the contact resolved
    let main = swap(&main, "       0.0       0.8", "       0.0       0.2");
    let main = swap(
        &main,
        "               0.001                 1.0",
        "               6e-05                 0.2",
    );
    let main = swap(
        &main,
        "         2         3         0         1      -2.0",
        &format!("         2         3         0         1{SF:>10}"),
    );
    let main = swap(
        &main,
        "                  13                   3                   2               -10.0",
        "                  13                   3                   3              -200.0",
    );
    let main = swap(
        &main,
        "*BOUNDARY_PRESCRIBED_MOTION_RIGID",
        "*DEFINE_CURVE\n         3\n                 0.0                 0.0\n               2e-05                 1.0\n               4e-05                 0.0\n*BOUNDARY_PRESCRIBED_MOTION_RIGID",
    );
    std::fs::write(dir.join("impact-mesh.k"), mesh).unwrap();
    let p = dir.join("deck.k");
    std::fs::write(&p, main).unwrap();
    p
}

fn crash(args: &[&str]) {
    let mut p = Proc::spawn("crash", &bin("crash"), args);
    assert!(p.wait(TIMEOUT).success(), "{}", p.log());
}

/// The deck as a scene (crash-master reads scenes): converted once.
fn scene() -> &'static Path {
    static S: OnceLock<PathBuf> = OnceLock::new();
    S.get_or_init(|| {
        let dir = out_dir("results-scene");
        let d = deck(&dir);
        let s = dir.join("impact.toml");
        crash(&["convert", d.to_str().unwrap(), s.to_str().unwrap()]);
        s
    })
}

fn run(tag: &str, input: &Path, args: &[&str]) -> PathBuf {
    crash_tests::cli::crash_run(input, &format!("results-{tag}"), args)
}

fn reference() -> &'static Path {
    static R: OnceLock<PathBuf> = OnceLock::new();
    R.get_or_init(|| run("ref", scene(), &["--threads", "1"]))
}

fn same_files(out: &Path) {
    for f in FILES {
        let a = std::fs::read(reference().join(f)).unwrap();
        let b = std::fs::read(out.join(f)).unwrap();
        assert!(
            a == b,
            "{f} differs from the single-thread run ({})",
            out.display()
        );
    }
}

#[test]
fn result_files_have_rows_and_are_identical_in_every_mode() {
    for f in FILES {
        let text = std::fs::read_to_string(reference().join(f)).unwrap();
        assert!(text.lines().count() > 2, "{f} has no rows:\n{text}");
    }
    same_files(&run("threads2", scene(), &["--threads", "2"]));
    same_files(&run(
        "workers3",
        scene(),
        &["--workers", "3", "--threads", "1"],
    ));
    let out = out_dir("results-grpc");
    let (mut m, url) = master(scene(), 2, &out, &[]);
    let mut w: Vec<_> = (0..2).map(|_| worker(&url, 1, &[])).collect();
    assert!(m.wait(TIMEOUT).success(), "{}", m.log());
    for p in &mut w {
        assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    }
    same_files(&out);
}

/// Data rows of a CSV as fields (no quoted names in these runs).
fn rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn matsum_energies_add_up_to_energy_csv() {
    let dir = reference();
    // energy.csv: time, kinetic, internal, hourglass, contact, damping, ...
    let totals: BTreeMap<String, Vec<f64>> = rows(&dir.join("energy.csv"))
        .into_iter()
        .map(|r| {
            (
                r[0].clone(),
                r[1..].iter().map(|v| v.parse().unwrap()).collect(),
            )
        })
        .collect();
    let mut sums: BTreeMap<String, [f64; 4]> = BTreeMap::new();
    for r in rows(&dir.join("matsum.csv")) {
        let s = sums.entry(r[1].clone()).or_insert([0.0; 4]);
        for k in 0..4 {
            s[k] += r[3 + k].parse::<f64>().unwrap();
        }
    }
    assert!(sums.len() > 2);
    for (t, s) in &sums {
        let e = totals
            .get(t)
            .unwrap_or_else(|| panic!("no energy.csv row at {t}"));
        // summed in body-id order as the energy ledger does: equal to the last bit
        let want = [e[0], e[1], e[2], e[4]];
        assert_eq!(
            s, &want,
            "at t = {t}: matsum sums {s:?}, energy.csv {want:?}"
        );
    }
}

#[test]
fn deck_history_node_moves_by_the_integral_of_its_velocity_curve() {
    // the deck itself through `crash run` (no conversion)
    let dir = out_dir("results-deck-input");
    let out = run("deck", &deck(&dir), &[]);
    let rows = rows(&out.join("nodout.csv"));
    let names: Vec<&str> = rows.iter().map(|r| r[3].as_str()).collect();
    assert!(names.contains(&"13") && names.contains(&"105"), "{names:?}");
    let last = rows.iter().rev().find(|r| r[3] == "105").unwrap();
    let t: f64 = last[1].parse().unwrap();
    assert!((t - END).abs() < 1e-12, "last row at {t}");
    let uz: f64 = last[6].parse().unwrap();
    // the integral of the piecewise-linear curve to the end time
    let mut area = 0.0;
    for w in CURVE.windows(2) {
        area += 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0);
    }
    area += CURVE[2].1 * (END - CURVE[2].0);
    let want = SF * area;
    // central differences: the midpoint sum of the velocity, exact on linear pieces;
    // a kink inside a step errs by at most h^2 |SF| |slope jump| / 8: with h ~ 1.1e-6 s
    // and the jump 1.16e5 1/s at 10 us that is 5e-7 m against 1.3e-3 m (4e-4 relative)
    assert!(
        ((uz - want) / want).abs() < 1e-3,
        "node 105 moved {uz} m, the curve's integral gives {want} m"
    );
    // the plate's history node 13 carries the load pulse: it moved
    let n13 = rows.iter().rev().find(|r| r[3] == "13").unwrap();
    assert!(n13[6].parse::<f64>().unwrap() != 0.0);
}
