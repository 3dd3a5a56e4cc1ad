//! Per-stage cost of a scene in one process (issue 17, point 6): the core driver on one
//! group (the bits of `crash run`), with each stage of the step timed inside
//! `Group::advance` (`StageTimes`): integration, element forces, contact; "other" is the
//! rest of the wall time of the stepping (the driver's dt rule, energies, reports).
//! Thread counts and repetitions are interleaved (1, 2, 1, 2, ...) so machine load
//! touches each alike; the table gives medians in ns per element-cycle and checks that
//! every thread count ends with the same state hash (exit 1 otherwise).
//!
//! Each repetition ends with a control: two 1-thread runs side by side in two threads
//! of this process. Their throughput against one run alone is what the machine gives two
//! independent jobs at that moment; the table's "machine" column is its median, and
//! "of machine" the 2-thread speed-up over it, taken rep by rep. Each rep also probes
//! the one-way core-to-core latency (two threads bouncing one atomic): 40-65 ns when the
//! host keeps this VM's vCPUs on one cache, about 200 ns when it has moved them apart,
//! and then every stage that reads what the other thread wrote slows down.
//!
//! Run: cargo bench -p crash-tests --bench stages -- SCENE [END_TIME [REPS [THREADS...]]]
//! (default: scenes/sphere-on-plate.toml to 1.2e-3 s, 3 repetitions, threads 1 2).
#![allow(clippy::unwrap_used)]

use crash_core::driver::Run;
use crash_core::Group;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Barrier;
use std::time::Instant;

struct Sample {
    wall: f64,
    integrate: f64,
    elements: f64,
    contact: f64,
    per: f64,
    hash: u64,
}

/// Above this one-way latency the vCPUs sit on different caches of the host.
const APART_NS: f64 = 120.0;

/// One-way latency [ns] of a cache line bounced between two threads (on two cores
/// when the machine has them free).
fn core_to_core() -> f64 {
    const ROUNDS: u64 = 200_000;
    let flag = AtomicU64::new(0);
    std::thread::scope(|s| {
        s.spawn(|| {
            for i in 0..ROUNDS {
                while flag.load(Ordering::Acquire) != 2 * i + 1 {
                    std::hint::spin_loop();
                }
                flag.store(2 * i + 2, Ordering::Release);
            }
        });
        let t0 = Instant::now();
        for i in 0..ROUNDS {
            flag.store(2 * i + 1, Ordering::Release);
            while flag.load(Ordering::Acquire) != 2 * i + 2 {
                std::hint::spin_loop();
            }
        }
        t0.elapsed().as_secs_f64() * 1e9 / (2 * ROUNDS) as f64
    })
}

/// Two 1-thread runs started together: the later one's wall, and both hashes.
fn pair(scene: &Path, end: f64) -> (f64, [u64; 2]) {
    let start = Barrier::new(2);
    std::thread::scope(|s| {
        let a = s.spawn(|| one(scene, end, 1, Some(&start)));
        let b = one(scene, end, 1, Some(&start));
        let a = a.join().unwrap();
        (a.wall.max(b.wall), [a.hash, b.hash])
    })
}

fn one(scene: &Path, end: f64, threads: usize, start: Option<&Barrier>) -> Sample {
    let built = crash_scene::load(scene).unwrap().build().unwrap();
    let mut cfg = built.run_config();
    cfg.end_time = end;
    let elements: usize = built.bodies.iter().map(|b| b.element_count()).sum();
    let mut group = Group::new(built.bodies, built.gravity);
    group.contact = built.contact;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut run = Run::new(group, cfg).unwrap();
        if let Some(b) = start {
            b.wait();
        }
        let t0 = Instant::now();
        run.run(|_| {}).unwrap();
        let wall = t0.elapsed().as_secs_f64();
        let st = run.group.times;
        let per = 1e9 / (elements as f64 * st.steps as f64);
        Sample {
            wall,
            integrate: st.integrate.as_secs_f64(),
            elements: st.elements.as_secs_f64(),
            contact: st.contact.as_secs_f64(),
            per,
            hash: crash_core::hash::state_hash(&run.group.bodies),
        }
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let scene = PathBuf::from(
        args.first()
            .cloned()
            .unwrap_or_else(|| "scenes/sphere-on-plate.toml".into()),
    );
    // cargo bench runs in the package directory: scenes are named from the workspace
    let scene = if scene.is_relative() && !scene.exists() {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(scene)
    } else {
        scene
    };
    let end: f64 = args.get(1).map_or(1.2e-3, |s| s.parse().unwrap());
    let reps: usize = args.get(2).map_or(3, |s| s.parse().unwrap());
    let threads: Vec<usize> = if args.len() > 3 {
        args[3..].iter().map(|s| s.parse().unwrap()).collect()
    } else {
        vec![1, 2]
    };
    let mut samples: Vec<Vec<Sample>> = threads.iter().map(|_| Vec::new()).collect();
    let mut machine: Vec<f64> = Vec::new();
    let mut latency: Vec<f64> = Vec::new();
    let mut pair_hashes: Vec<u64> = Vec::new();
    for r in 0..reps {
        let before = core_to_core();
        for (k, &t) in threads.iter().enumerate() {
            let s = one(&scene, end, t, None);
            eprintln!(
                "rep {r}, {t} thread(s): {:.2} s, hash {:016x}",
                s.wall, s.hash
            );
            samples[k].push(s);
        }
        let (w, pair_hash) = pair(&scene, end);
        pair_hashes.extend(pair_hash);
        let alone = samples[0][r].wall;
        let ns = core_to_core();
        eprintln!(
            "rep {r}, two 1-thread runs side by side: {w:.2} s ({:.2}x the throughput of one); core-to-core {before:.0} ns before the rep, {ns:.0} ns after",
            2.0 * alone / w
        );
        // a rep counts as "apart" if either probe around it says so
        latency.push(ns.max(before));
        machine.push(2.0 * alone / w);
    }
    println!(
        "{} to {end} s, medians of {reps} (ns per element-cycle):",
        scene.display()
    );
    println!(
        "| threads | integrate | elements | contact | other | whole step | speed-up | machine | of machine |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let cap = median(machine.clone());
    let base = median(samples[0].iter().map(|s| s.wall * s.per).collect());
    let mut hashes: Vec<u64> = Vec::new();
    for (k, &t) in threads.iter().enumerate() {
        let m = |f: &dyn Fn(&Sample) -> f64| median(samples[k].iter().map(f).collect());
        let (i, e, c) = (
            m(&|s| s.integrate * s.per),
            m(&|s| s.elements * s.per),
            m(&|s| s.contact * s.per),
        );
        let w = m(&|s| s.wall * s.per);
        let o = m(&|s| (s.wall - s.integrate - s.elements - s.contact) * s.per);
        // rep by rep: this thread count's speed-up over what the machine gave two jobs
        let of = median(
            (0..reps)
                .map(|r| samples[0][r].wall / samples[k][r].wall / machine[r].min(t as f64))
                .collect(),
        );
        println!(
            "| {t} | {i:.1} | {e:.1} | {c:.1} | {o:.1} | {w:.1} | {:.2}x | {:.2}x | {:.0} % |",
            base / w,
            cap.min(t as f64),
            100.0 * of
        );
        hashes.extend(samples[k].iter().map(|s| s.hash));
    }
    println!(
        "core-to-core latency, median of the reps: {:.0} ns (over {APART_NS} ns the host had the vCPUs apart)",
        median(latency.clone())
    );
    let last = threads.len() - 1;
    for (apart, what) in [(false, "together"), (true, "apart")] {
        let ups: Vec<f64> = (0..reps)
            .filter(|&r| (latency[r] > APART_NS) == apart)
            .map(|r| samples[0][r].wall / samples[last][r].wall)
            .collect();
        if !ups.is_empty() {
            println!(
                "{} threads against {}, reps with the vCPUs {what}: {:.2}x (median of {})",
                threads[last],
                threads[0],
                median(ups.clone()),
                ups.len()
            );
        }
    }
    // the side-by-side runs are 1-thread runs too
    hashes.extend(pair_hashes);
    hashes.sort_unstable();
    hashes.dedup();
    if hashes.len() != 1 {
        eprintln!("state hashes differ between thread counts: {hashes:016x?}");
        std::process::exit(1);
    }
    println!(
        "same final state hash {:016x} for every thread count",
        hashes[0]
    );
}
