//! A keyword deck of a few thousand shells with contact (written here): `crash run
//! deck.k` and `crash run` of the scene `crash convert` writes end with the same scene
//! hash and the same final state hash (the conversion loses nothing that runs).
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_tests::procs::{bin, out_dir, Proc};
use std::path::Path;
use std::time::Duration;

const TIMEOUT: Duration = Duration::from_secs(300);

/// A 50 x 50 plate of quads held on its edges and a 20 x 20 tile 0.05 mm above it
/// (both 2 mm thick) thrown down at 5 m/s: it touches at 10 us of 20; 2900 shells.
fn deck() -> String {
    let (n, m) = (50, 20);
    let mut s = String::from("*KEYWORD\n*CONTROL_TERMINATION\n2.0e-5\n*NODE\n");
    let id = |i: usize, j: usize| 1 + j * (n + 1) + i;
    for j in 0..=n {
        for i in 0..=n {
            let h = 0.6 / n as f64;
            s += &format!(
                "{},{:e},{:e},0.0\n",
                id(i, j),
                -0.3 + h * i as f64,
                -0.3 + h * j as f64
            );
        }
    }
    let tid = |i: usize, j: usize| 100_000 + 1 + j * (m + 1) + i;
    for j in 0..=m {
        for i in 0..=m {
            let h = 0.1 / m as f64;
            s += &format!(
                "{},{:e},{:e},2.05e-3\n",
                tid(i, j),
                -0.05 + h * i as f64,
                -0.05 + h * j as f64
            );
        }
    }
    s += "*ELEMENT_SHELL\n";
    for j in 0..n {
        for i in 0..n {
            s += &format!(
                "{},1,{},{},{},{}\n",
                1 + j * n + i,
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            );
        }
    }
    for j in 0..m {
        for i in 0..m {
            s += &format!(
                "{},2,{},{},{},{}\n",
                100_000 + 1 + j * m + i,
                tid(i, j),
                tid(i + 1, j),
                tid(i + 1, j + 1),
                tid(i, j + 1)
            );
        }
    }
    s += "*PART\nplate\n1,1,1\ntile\n2,1,1\n*SECTION_SHELL\n1\n2.0e-3\n";
    s += "*MAT_ELASTIC\n1,2700.0,7.0e10,0.33\n";
    s += &format!(
        "*SET_NODE_LIST_GENERATE\n1\n{},{},{},{}\n",
        id(0, 0),
        id(n, 0),
        id(0, n),
        id(n, n)
    );
    s += "*SET_NODE_LIST\n2\n";
    let sides: Vec<String> = (1..n)
        .flat_map(|j| [id(0, j), id(n, j)])
        .map(|k| k.to_string())
        .collect();
    for c in sides.chunks(8) {
        s += &c.join(",");
        s += "\n";
    }
    s += "*BOUNDARY_SPC_SET\n1,0,1,1,1,1,1,1\n2,0,1,1,1,1,1,1\n";
    s += "*SET_PART_LIST\n7\n2\n*INITIAL_VELOCITY_GENERATION\n7,1,0.0,0.0,0.0,-5.0\n0.0,0.0,0.0,0.0,0.0,1.0\n";
    s += "*CONTACT_AUTOMATIC_SURFACE_TO_SURFACE\n2,1,3,3\n";
    s += "*END\n";
    s
}

fn crash(args: &[&str]) {
    let mut p = Proc::spawn("crash", &bin("crash"), args);
    assert!(p.wait(TIMEOUT).success(), "{}", p.log());
}

fn summary_field(out: &Path, key: &str) -> String {
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v[key].as_str().unwrap().to_string()
}

#[test]
fn deck_of_thousands_of_shells_runs_to_the_same_hash_as_its_converted_scene() {
    let dir = out_dir("big-deck");
    let d = dir.join("big.k");
    std::fs::write(&d, deck()).unwrap();
    let (a, b) = (dir.join("from-deck"), dir.join("from-scene"));
    let common = ["--quiet", "--no-pictures", "--threads", "2"];
    let run = |input: &Path, out: &Path| {
        let mut args = vec![
            "run",
            input.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(&common);
        crash(&args);
    };
    run(&d, &a);
    let scene = dir.join("scene").join("big.toml");
    crash(&["convert", d.to_str().unwrap(), scene.to_str().unwrap()]);
    run(&scene, &b);
    let steps: u64 = std::fs::read_to_string(a.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["steps"].as_u64())
        .unwrap();
    assert!(steps > 2, "only {steps} steps");
    // the tile reached the plate: rcforc.csv has a force row
    let rc = std::fs::read_to_string(a.join("rcforc.csv")).unwrap();
    assert!(rc.lines().count() > 1, "no contact force row:\n{rc}");
    assert_eq!(
        summary_field(&a, "scene_hash"),
        summary_field(&b, "scene_hash")
    );
    assert_eq!(
        summary_field(&a, "final_state_hash"),
        summary_field(&b, "final_state_hash")
    );
}
