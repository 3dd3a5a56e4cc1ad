//! Keeps the other threads of a rayon pool awake while a run steps.
//!
//! A step is a dozen parallel regions (element forces, integration, contact passes per
//! body) separated by short serial stretches. A rayon worker with nothing to do goes to
//! sleep within some tens of microseconds, and waking it costs about 35 µs on the
//! development VM: longer than most regions of the showcase, so the second thread took
//! part in few of them. A region of 2 x 29 µs of work after a serial gap
//! (`cargo run --release -p crash-core --example wake_latency`, docs/performance.md
//! "Threads kept awake"): 29-30 µs with the keeper at any gap, 64.7 µs (more than the
//! serial 57.8) without it once the gap reaches 50 µs.
//!
//! The keeper is a job on each other pool thread that asks the pool for work
//! (`rayon::yield_now`) in a loop until the guard is dropped, yielding the core to the
//! OS now and then (the frame writer may need it). Where work runs never changes what
//! is computed: every result stays bit-identical (tests `determinism`, `simd_paths`).
//! It spends the other cores' idle time in spinning, as an OpenMP code with an active
//! wait policy does; `--threads 1` starts none.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// Idle polls between two yields of the core to the OS.
const POLLS_PER_YIELD: u32 = 64;

thread_local! {
    /// This thread runs a keeper (a keeper must not start a second one inside it).
    static KEEPING: Cell<bool> = const { Cell::new(false) };
}

/// While alive, the other threads of the current rayon pool stay awake and take work as
/// soon as it is pushed. Start it on the thread that steps the run.
#[derive(Debug)]
pub struct KeepAwake {
    stop: Arc<AtomicBool>,
    /// Keepers polling now.
    running: Arc<AtomicUsize>,
}

impl KeepAwake {
    /// Keepers on the other threads of the pool this thread belongs to (at most one less
    /// than the machine's cores); `None` outside a pool, in a pool of one thread or on
    /// one core (nothing to keep awake).
    pub fn start() -> Option<Self> {
        if !enabled() {
            return None;
        }
        let home = rayon::current_thread_index()?;
        // never more spinning threads than cores: a pool larger than the machine keeps
        // only as many awake as there are other cores
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let others = rayon::current_num_threads().min(cores).saturating_sub(1);
        if others == 0 {
            return None;
        }
        let stop = Arc::new(AtomicBool::new(false));
        let running = Arc::new(AtomicUsize::new(0));
        for _ in 0..others {
            let (s, r) = (stop.clone(), running.clone());
            rayon::spawn(move || keep(s, r, home));
        }
        Some(Self { stop, running })
    }

    /// Keepers polling now (they start as the pool picks their jobs up).
    pub fn running(&self) -> usize {
        self.running.load(Ordering::Relaxed)
    }

    /// Stop the keepers and wait until none polls any more.
    pub fn stop(self) {
        self.stop.store(true, Ordering::Relaxed);
        while self.running() > 0 {
            std::thread::yield_now();
        }
    }
}

impl Drop for KeepAwake {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// `CRASH_KEEP_AWAKE=0` (or `off`) in the environment turns the keepers off: on a
/// machine shared with other work the idle threads then sleep (and the A/B of
/// docs/performance.md compares the two in one binary).
fn enabled() -> bool {
    static ON: OnceLock<bool> = OnceLock::new();
    *ON.get_or_init(|| {
        !matches!(
            std::env::var("CRASH_KEEP_AWAKE").as_deref(),
            Ok("0") | Ok("off")
        )
    })
}

/// One keeper: poll the pool for work until stopped. On the stepping thread (which may
/// pick the job up while it waits in a join) or on a thread that already keeps, hand
/// the job back to the pool instead: it must not hold that thread.
fn keep(stop: Arc<AtomicBool>, running: Arc<AtomicUsize>, home: usize) {
    if stop.load(Ordering::Relaxed) {
        return;
    }
    if rayon::current_thread_index() == Some(home) || KEEPING.with(Cell::get) {
        rayon::spawn(move || keep(stop, running, home));
        return;
    }
    KEEPING.with(|k| k.set(true));
    running.fetch_add(1, Ordering::Relaxed);
    let mut idle = 0u32;
    while !stop.load(Ordering::Relaxed) {
        match rayon::yield_now() {
            Some(rayon::Yield::Executed) => idle = 0,
            Some(rayon::Yield::Idle) => {
                idle += 1;
                if idle.is_multiple_of(POLLS_PER_YIELD) {
                    std::thread::yield_now();
                } else {
                    std::hint::spin_loop();
                }
            }
            None => break,
        }
    }
    running.fetch_sub(1, Ordering::Relaxed);
    KEEPING.with(|k| k.set(false));
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    #[test]
    fn keepers_start_only_in_a_pool_of_more_than_one_thread_and_stop_with_the_guard() {
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool");
        assert!(one.install(KeepAwake::start).is_none());
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("pool");
        two.install(|| {
            let Some(k) = KeepAwake::start() else {
                // a one-core machine keeps nothing awake
                assert_eq!(
                    std::thread::available_parallelism().map_or(1, |n| n.get()),
                    1
                );
                return;
            };
            // work runs through the keeper and gives the serial answer
            let v: Vec<u64> = (0..10_000).collect();
            let sum: u64 = v
                .par_chunks(100)
                .map(|c| c.iter().map(|i| i * i).sum::<u64>())
                .sum();
            assert_eq!(sum, (0..10_000u64).map(|i| i * i).sum::<u64>());
            // the keeper runs on the other thread, never on this one
            let t = std::time::Instant::now();
            while k.running() == 0 && t.elapsed().as_secs() < 10 {
                std::thread::yield_now();
            }
            assert_eq!(k.running(), 1);
            k.stop();
        });
    }
}
