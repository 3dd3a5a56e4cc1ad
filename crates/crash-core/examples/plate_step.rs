//! The whole step of the shell_step bench's plate on one thread, timed in many short
//! runs: min, first quartile and median ns per element-cycle. On a shared, noisy host
//! these quantiles separate two builds where criterion's 10 samples do not (the
//! minimum is the run least disturbed by other tenants). Compare builds in one sitting,
//! alternating them.
//!
//! Run: `cargo run --release -p crash-core --example plate_step -- [N] [RUNS] [tri|quad]`
//! (an N x N plate, default 224 x 224 triangles = 100 352 elements as in shell_step;
//! RUNS runs of 5 steps, default 40). It prints the final state hash too: runs of the
//! same N, RUNS and kind compare bit for bit (e.g. `CRASH_SUMMED=0|1`, crash-core
//! `summed`).

use crash_core::shapes::{bench_plate, ElementKind};
use crash_core::{Clock, Group, Vec3};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, default: usize| -> usize {
        args.get(i).map_or(default, |v| {
            v.parse()
                .unwrap_or_else(|_| panic!("argument {i} ({v}) is not a count"))
        })
    };
    let n = arg(1, 224);
    let runs = arg(2, 40).max(1);
    let kind = match args.get(3).map(String::as_str) {
        None | Some("tri") => ElementKind::Tri,
        Some("quad") => ElementKind::Quad,
        Some(k) => panic!("element kind {k}: tri or quad"),
    };
    let body = bench_plate(n, n, kind);
    let elements = body.element_count() as f64;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread pool");
    let mut group = Group::new(vec![body], Vec3::zeros());
    pool.install(|| {
        group.start().expect("a stable start");
        let mut clock = Clock::default();
        let mut ns = Vec::with_capacity(runs);
        for _ in 0..runs {
            let t = Instant::now();
            for _ in 0..5 {
                group.advance(&clock, 1e-7).expect("a stable step");
                clock = clock.after(1e-7);
            }
            ns.push(t.elapsed().as_secs_f64() / 5.0 / elements * 1e9);
        }
        ns.sort_by(f64::total_cmp);
        println!(
            "{kind:?} {elements} elements, whole step on 1 thread: min {:.1} p25 {:.1} median {:.1} ns per element-cycle",
            ns[0],
            ns[ns.len() / 4],
            ns[ns.len() / 2]
        );
        println!(
            "state hash after {} steps: {:016x}",
            5 * runs,
            crash_core::hash::state_hash(&group.bodies)
        );
    });
}
