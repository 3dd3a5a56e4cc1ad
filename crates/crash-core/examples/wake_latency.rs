//! What a parallel region costs after a serial gap, with and without the pool's other
//! threads kept awake (crash_core::awake): two chunks of ~30 µs of work on a pool of
//! two threads, after a busy serial gap of 0-300 µs, medians of 2000 regions.
//! `cargo run --release -p crash-core --example wake_latency`

use crash_core::awake::KeepAwake;
use rayon::prelude::*;
use std::time::{Duration, Instant};

fn busy(d: Duration) {
    let t = Instant::now();
    while t.elapsed() < d {
        std::hint::spin_loop();
    }
}

fn regions(v: &mut [f64], gap_us: u64) -> (f64, f64) {
    let mut ts: Vec<f64> = (0..2000)
        .map(|_| {
            busy(Duration::from_micros(gap_us));
            let t = Instant::now();
            let half = v.len() / 2;
            v.par_chunks_mut(half).for_each(|c| {
                for x in c.iter_mut() {
                    *x = x.sqrt() + 1.0;
                }
            });
            t.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    ts.sort_by(f64::total_cmp);
    (ts[ts.len() / 2], ts[ts.len() * 9 / 10])
}

fn main() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("a pool of two threads");
    let mut v = vec![1.0f64; 2 * 32768];
    let t = Instant::now();
    for x in v.iter_mut() {
        *x = x.sqrt() + 1.0;
    }
    println!(
        "serial work of one region: {:.1} us",
        t.elapsed().as_secs_f64() * 1e6
    );
    println!("| serial gap [us] | region, threads asleep [us] | region, kept awake [us] |");
    println!("| --- | --- | --- |");
    for gap in [0u64, 5, 20, 50, 100, 300] {
        let (asleep, asleep90) = pool.install(|| regions(&mut v, gap));
        let (awake, awake90) = pool.install(|| {
            let k = KeepAwake::start();
            let r = regions(&mut v, gap);
            if let Some(k) = k {
                k.stop();
            }
            r
        });
        println!("| {gap} | {asleep:.1} (p90 {asleep90:.1}) | {awake:.1} (p90 {awake90:.1}) |");
    }
}
