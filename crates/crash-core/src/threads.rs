//! Thread counts a user asks for, against the cores the machine offers.

/// The cores this process may run on (1 if the system cannot tell).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// A note for the console when `requested` compute threads exceed the cores: the
/// threads then take turns on the cores and every parallel stage waits for the slowest,
/// so the run is slower than with one thread per core (results are unchanged: they do
/// not depend on the thread count).
pub fn oversubscription(requested: usize, cores: usize) -> Option<String> {
    (requested > cores).then(|| {
        format!(
            "{requested} threads asked for, but this machine offers {cores} core{}: threads \
             will share cores and the run will be slower, not faster (results are the same \
             for any thread count); use --threads {cores} or fewer",
            if cores == 1 { "" } else { "s" }
        )
    })
}

/// Compute threads per in-process worker: `requested`, else the cores shared out among
/// the `workers` (at least one each).
pub fn per_worker(requested: Option<usize>, workers: usize, cores: usize) -> usize {
    requested.unwrap_or(cores / workers.max(1)).max(1)
}

/// Elements per compute unit below which `crash run` (without `--workers`) uses fewer
/// units: a domain of fewer elements costs more in its exchanges than it computes
/// (docs/performance.md, session 32: a 1 000-element scene is no faster on 2 units, a
/// 4 400-element one 1.65x).
pub const UNIT_ELEMENTS: usize = 1024;

/// `crash run` without `--workers`: (in-process workers, threads each) for a scene of
/// `elements` with `threads` compute threads asked for (the cores when not given). Each
/// thread becomes a domain of its own, an in-process worker of one thread (the scene's
/// large groups split by elements): workers that each own their part's data scale
/// further on two cores than threads that share every loop (1.79x against 1.39x on the
/// showcase, docs/performance.md, session 32); fewer domains when the scene has fewer
/// than `UNIT_ELEMENTS` elements a domain. `splits`: the master may split the scene's
/// groups (crash-master splits none that holds a kinematic copy or a history node);
/// when it may not and there are fewer than two deformable `bodies` a domain, domains
/// would idle: one worker whose threads share the loops. Same bits either way.
pub fn domains(
    threads: Option<usize>,
    elements: usize,
    cores: usize,
    splits: bool,
    bodies: usize,
) -> (usize, usize) {
    let total = threads.unwrap_or(cores).max(1);
    let units = total.min(elements / UNIT_ELEMENTS).max(1);
    if splits || bodies >= 2 * units {
        (units, 1)
    } else {
        (1, total)
    }
}

/// `oversubscription` for `workers` in-process workers of `threads` threads each (they
/// compute at once, so their threads add up).
pub fn oversubscription_of_workers(workers: usize, threads: usize, cores: usize) -> Option<String> {
    if workers <= 1 {
        return oversubscription(threads, cores);
    }
    let total = workers * threads;
    (total > cores).then(|| {
        format!(
            "{workers} workers x {threads} thread{} = {total} threads asked for, but this \
             machine offers {cores} core{}: threads will share cores and the run will be \
             slower, not faster (results are the same for any count); keep workers x \
             threads at {cores} or fewer",
            if threads == 1 { "" } else { "s" },
            if cores == 1 { "" } else { "s" }
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_note_only_when_threads_exceed_cores() {
        assert_eq!(oversubscription(2, 2), None);
        assert_eq!(oversubscription(1, 4), None);
        let note = oversubscription(8, 2).expect("8 threads on 2 cores");
        assert!(
            note.contains("8 threads") && note.contains("2 cores") && note.contains("--threads 2")
        );
        assert!(oversubscription(2, 1).expect("2 on 1").contains("1 core:"));
    }

    #[test]
    fn a_domain_per_thread_for_scenes_large_enough() {
        assert_eq!(domains(None, 24_080, 2, true, 2), (2, 1), "the showcase");
        assert_eq!(domains(Some(1), 24_080, 2, true, 2), (1, 1));
        assert_eq!(
            domains(Some(4), 24_080, 2, true, 2),
            (4, 1),
            "the note says"
        );
        assert_eq!(domains(None, 3_000, 8, true, 2), (2, 1), "fewer domains");
        assert_eq!(
            domains(None, 1_000, 2, true, 2),
            (1, 1),
            "a tiny scene: one"
        );
        assert_eq!(domains(None, 0, 0, true, 0), (1, 1));
        // no split: one body on a kinematic wall shares the loops, ten spheres spread
        assert_eq!(domains(None, 24_080, 2, false, 1), (1, 2));
        assert_eq!(domains(None, 16_000, 2, false, 10), (2, 1));
    }

    #[test]
    fn workers_share_the_cores_and_their_threads_add_up() {
        assert_eq!(per_worker(None, 2, 2), 1);
        assert_eq!(per_worker(None, 1, 8), 8);
        assert_eq!(per_worker(None, 3, 2), 1);
        assert_eq!(per_worker(Some(2), 4, 2), 2);
        assert_eq!(oversubscription_of_workers(2, 1, 2), None);
        let note = oversubscription_of_workers(2, 2, 2).expect("4 threads on 2 cores");
        assert!(note.contains("2 workers x 2 threads = 4 threads"), "{note}");
        assert_eq!(
            oversubscription_of_workers(1, 4, 2),
            oversubscription(4, 2),
            "one worker: the plain note"
        );
    }
}
