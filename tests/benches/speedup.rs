//! Speed-up of worker processes on the ten-spheres-three-plates-small scene (4 400
//! elements), shortened to `END_TIME` with frames only at the start and the end: crash-master with 1 worker x 1 thread, 2 workers
//! x 1 thread, and 1 worker x 2 threads, each run `REPS` times; prints the median wall
//! time of the run (summary.json `wall_time_s`: from the first command to the last
//! frame, without process start-up) and the speed-up over 1 x 1.
//! Run: cargo bench -p crash-tests --bench speedup
#![allow(clippy::unwrap_used)]

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

use crash_tests::procs::{master_bin, worker_bin};
const END_TIME: &str = "1e-3";
const REPS: usize = 3;

/// Wall time of the run [s] and its compute stage (slowest worker per step) [s].
fn run(scene: &Path, workers: usize, threads: usize, out: &Path) -> (f64, f64) {
    let _ = std::fs::remove_dir_all(out);
    let mut m = Command::new(master_bin())
        .args([
            scene.to_str().unwrap(),
            "--listen",
            "127.0.0.1:0",
            "--workers",
            &workers.to_string(),
            "--out",
            out.to_str().unwrap(),
            "--end-time",
            END_TIME,
            "--output-interval",
            END_TIME,
        ])
        .env("RUST_LOG", "warn")
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(m.stderr.take().unwrap()).lines();
    let addr = loop {
        let l = lines.next().unwrap().unwrap();
        if let Some(a) = l.strip_prefix("crash-master: listening on ") {
            break a.trim().to_string();
        }
    };
    let mut ws: Vec<_> = (0..workers)
        .map(|_| {
            Command::new(worker_bin())
                .args([
                    "--master",
                    &format!("http://{addr}"),
                    "--threads",
                    &threads.to_string(),
                ])
                .env("RUST_LOG", "warn")
                .stderr(Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for l in lines.map_while(Result::ok) {
        eprintln!("  {l}");
    }
    assert!(m.wait().unwrap().success());
    for w in &mut ws {
        let _ = w.wait();
    }
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    let cycles = s.elements as f64 * s.steps as f64;
    (
        s.wall_time_s,
        s.ns_per_element_cycle["compute"] * cycles * 1e-9,
    )
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    // cargo bench passes --bench; any other argument filters nothing here
    let scene = crash_tests::fixtures::scene("ten-spheres-three-plates-small.toml");
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("speedup-run");
    let mut base = None;
    for (workers, threads) in [(1, 1), (2, 1), (1, 2)] {
        let runs: Vec<(f64, f64)> = (0..REPS)
            .map(|_| run(&scene, workers, threads, &out))
            .collect();
        let wall: Vec<f64> = runs.iter().map(|r| r.0).collect();
        let med = median(wall.clone());
        let compute = median(runs.iter().map(|r| r.1).collect());
        let b = *base.get_or_insert(med);
        println!(
            "speedup/{workers}x{threads}: median wall {med:.3} s (runs {wall:.3?}; compute stage {compute:.3} s), speed-up over 1x1: {:.2}",
            b / med
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}
