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
}
