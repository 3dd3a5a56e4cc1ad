//! The scaling benchmark (issue 16, point 6): one scene in nine modes, timed in one
//! sitting with the repetitions interleaved (mode A, B, C, D, then again), so machine
//! load affects every mode alike:
//!
//! - `crash run --workers 1 --threads 1` and `--workers 1 --threads 2` (one process, one
//!   worker whose threads share the element and node loops),
//! - `crash-master` + 1 and + 2 `crash-worker` processes x 1 thread (gRPC on loopback),
//! - `crash-master --split auto` + 2 workers: a group above its fair share is split
//!   over both workers by elements (the holders send each other their part states
//!   directly: one exchange with the master per step and one message each way between
//!   the workers),
//! - `crash-master` + 2 workers x 1 thread, all with `--idle-spin` (a SCHED_IDLE
//!   spinner per process keeps vCPUs from halting between messages),
//! - `crash run --workers 2 --split auto --threads 1`: the split in one process, its two
//!   workers computing at once (since session 27; before, one after the other): the
//!   cluster without its processes, codec and sockets; what `crash run --threads 2`
//!   does without `--workers` since session 32 (a domain per thread),
//! - `crash-master --split auto --no-direct-halo` + 2 workers: the split with the part
//!   states relayed through the master (two exchanges per step),
//! - `crash-master --split auto` + 2 workers with `--poll-us 0`: workers that block at
//!   once for each command and halo instead of polling first (their default).
//!
//! Prints, per mode, the median wall time of the run (summary.json `wall_time_s`: from
//! the first command to the last frame), ns per element-cycle, the speed-up over
//! `--threads 1`, the barrier's median per step and its parts, the workers' compute
//! times summed (summary.json `cluster.compute_ns_per_worker`) over the first mode's,
//! and checks that every mode ends with the same final state hash (exit 1 otherwise).
//!
//! Run: cargo bench -p crash-tests --bench scaling -- SCENE [END_TIME [REPS [MODES]]]
//! (default: scenes/ten-spheres-three-plates-small.toml to 1e-3 s, 3 repetitions, all
//! modes; MODES picks some by their place in the list above, e.g. `0,4`: 1 thread and
//! the split; the speed-up is over the first mode picked).
#![allow(clippy::unwrap_used)]

use crash_io::Summary;
use crash_tests::procs::{bin, master_bin, worker_bin};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Local {
        threads: usize,
        /// In-process workers, and `--split auto` when more than one.
        workers: usize,
    },
    Cluster {
        workers: usize,
        split: bool,
        spin: bool,
        /// `--no-direct-halo`: the master relays the part states.
        relay: bool,
        /// Workers with `--poll-us 0`: they block at once.
        block: bool,
    },
}

impl Mode {
    fn label(self) -> String {
        match self {
            Mode::Local {
                threads,
                workers: 1,
            } => format!("crash run --workers 1 --threads {threads}"),
            Mode::Local { threads, workers } => {
                format!("crash run --workers {workers} --split auto --threads {threads}")
            }
            Mode::Cluster {
                workers,
                split,
                spin,
                relay,
                block,
            } => format!(
                "master{}{} + {workers} worker(s) x 1 thread{}{}",
                if split {
                    " --split auto"
                } else {
                    " --split off"
                },
                if relay { " --no-direct-halo" } else { "" },
                if spin { ", --idle-spin" } else { "" },
                if block { ", --poll-us 0" } else { "" }
            ),
        }
    }
}

fn run(mode: Mode, scene: &Path, end: &str, out: &Path) -> Summary {
    let _ = std::fs::remove_dir_all(out);
    let out_s = out.to_str().unwrap();
    let scene_s = scene.to_str().unwrap();
    match mode {
        Mode::Local { threads, workers } => {
            let split: &[&str] = if workers > 1 {
                &["--split", "auto"]
            } else {
                &[]
            };
            let st = Command::new(bin("crash"))
                .args(["run", scene_s, "--threads", &threads.to_string()])
                .args(["--workers", &workers.to_string()])
                .args(split)
                .args(["--end-time", end, "--output-interval", end, "--out", out_s])
                .args(["--quiet", "--no-pictures", "--allow-warnings"])
                .env("RUST_LOG", "warn")
                .stderr(Stdio::null())
                .status()
                .unwrap();
            assert!(st.success(), "{}: {st}", mode.label());
        }
        Mode::Cluster {
            workers,
            split,
            spin,
            relay,
            block,
        } => {
            let spin_arg: &[&str] = if spin { &["--idle-spin"] } else { &[] };
            let block_arg: &[&str] = if block { &["--poll-us", "0"] } else { &[] };
            let relay_arg: &[&str] = if relay { &["--no-direct-halo"] } else { &[] };
            let mut m = Command::new(master_bin())
                .args([scene_s, "--listen", "127.0.0.1:0"])
                .args(spin_arg)
                .args(relay_arg)
                .args(["--split", if split { "auto" } else { "off" }])
                .args(["--workers", &workers.to_string(), "--out", out_s])
                .args(["--end-time", end, "--output-interval", end])
                .env("RUST_LOG", "warn")
                .env_remove("CRASH_SECRET")
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
                        .args(["--master", &format!("http://{addr}"), "--threads", "1"])
                        .args(spin_arg)
                        .args(block_arg)
                        .env("RUST_LOG", "warn")
                        .env_remove("CRASH_SECRET")
                        .stderr(Stdio::null())
                        .spawn()
                        .unwrap()
                })
                .collect();
            for l in lines.map_while(Result::ok) {
                if l.contains("error") {
                    eprintln!("  {l}");
                }
            }
            let st = m.wait().unwrap();
            for w in &mut ws {
                let _ = w.wait();
            }
            assert!(st.success(), "{}: {st}", mode.label());
        }
    }
    crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    // cargo bench passes --bench: positional arguments only
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let scene = args.first().map_or_else(
        || crash_tests::fixtures::scene("ten-spheres-three-plates-small.toml"),
        |s| {
            let p = PathBuf::from(s);
            if p.is_absolute() {
                p
            } else {
                crash_tests::fixtures::root().join(p)
            }
        },
    );
    let end = args.get(1).cloned().unwrap_or_else(|| "1e-3".into());
    let reps: usize = args.get(2).and_then(|r| r.parse().ok()).unwrap_or(3);
    // (workers, split, spin, relay, block) of a cluster mode
    let cluster = |workers, split, spin, relay, block| Mode::Cluster {
        workers,
        split,
        spin,
        relay,
        block,
    };
    let modes = [
        Mode::Local {
            threads: 1,
            workers: 1,
        },
        Mode::Local {
            threads: 2,
            workers: 1,
        },
        cluster(1, false, false, false, false),
        cluster(2, false, false, false, false),
        cluster(2, true, false, false, false),
        cluster(2, false, true, false, false),
        Mode::Local {
            threads: 1,
            workers: 2,
        },
        cluster(2, true, false, true, false),
        cluster(2, true, false, false, true),
    ];
    let modes: Vec<Mode> = match args.get(3) {
        Some(pick) => pick
            .split(',')
            .map(
                |k| match k.trim().parse::<usize>().ok().and_then(|k| modes.get(k)) {
                    Some(m) => *m,
                    None => {
                        eprintln!(
                            "scaling: MODES {pick:?}: each must be 0..{}",
                            modes.len() - 1
                        );
                        std::process::exit(2);
                    }
                },
            )
            .collect(),
        None => modes.to_vec(),
    };
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("scaling-run");
    let mut runs: Vec<Vec<Summary>> = vec![Vec::new(); modes.len()];
    for _ in 0..reps {
        for (k, &mode) in modes.iter().enumerate() {
            runs[k].push(run(mode, &scene, &end, &out));
        }
    }
    let _ = std::fs::remove_dir_all(&out);
    let s0 = &runs[0][0];
    println!(
        "scaling: {} to {end} s ({} elements, {} steps), {reps} interleaved runs per mode, medians",
        scene.display(),
        s0.elements,
        s0.steps
    );
    println!(
        "| mode | wall [s] | ns/element-cycle | speed-up vs the first | barrier median [us/step] | master codec / worker codec / master merge / wire+wake [us] | master work [us/step] | worker compute, summed, vs the first | final hash |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let base = median(runs[0].iter().map(|s| s.wall_time_s).collect());
    // the workers' compute summed (one process: its in-process workers')
    let work = |r: &[Summary]| {
        median(
            r.iter()
                .map(|s| s.cluster.compute_ns_per_worker.iter().sum::<u64>() as f64)
                .collect(),
        )
    };
    let base_work = work(&runs[0]);
    let mut hashes = Vec::new();
    for (mode, r) in modes.iter().zip(&runs) {
        let wall = median(r.iter().map(|s| s.wall_time_s).collect());
        let ns = median(r.iter().map(|s| s.ns_per_element_cycle["total"]).collect());
        let part = |k: &str| {
            median(
                r.iter()
                    .map(|s| s.barrier_us_per_step.get(k).copied().unwrap_or(f64::NAN))
                    .collect(),
            )
        };
        println!(
            "| {} | {wall:.2} | {ns:.1} | {:.2}x | {:.0} | {:.1} / {:.1} / {:.1} / {:.1} | {:.1} | {:.2}x | {} |",
            mode.label(),
            base / wall,
            part("median"),
            part("master_codec"),
            part("worker_codec"),
            part("master_merge"),
            part("wire_wake"),
            part("master_work"),
            work(r) / base_work,
            r[0].final_state_hash
        );
        hashes.extend(r.iter().map(|s| s.final_state_hash.clone()));
    }
    if hashes.iter().any(|h| *h != hashes[0]) {
        eprintln!("scaling: the modes disagree on the final state hash: {hashes:?}");
        std::process::exit(1);
    }
    println!(
        "every mode and run ends with the same final state hash {}",
        hashes[0]
    );
}
