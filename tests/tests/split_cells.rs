//! What a user sees of a group split over workers (issue 16 point 5): each frame's
//! `worker` and `part` cells give, for every element of a split body, the part that
//! computes it and that part's worker. Invariants on the showcase split over 2
//! in-process workers (the sphere and the plate each cut in 2): each body's elements
//! fall in parts 0 and 1, each part on one worker, the two on different workers, the
//! cut balanced, part 0 on the group's home; the frames read back as written.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_tests::cli::{crash_run, last_frame};
use crash_tests::fixtures::scene;
use std::collections::BTreeSet;

#[test]
fn every_element_of_a_split_body_names_its_part_and_that_parts_worker() {
    let args = [
        "--workers",
        "2",
        "--threads",
        "1",
        "--split",
        "auto",
        "--end-time",
        "2e-5",
    ];
    let out = crash_run(&scene("sphere-on-plate.toml"), "split-cells", &args);
    let last = last_frame(&out);
    // the sphere above the share is cut; the plate, placed whole, would load the
    // sphere's first part's worker 1.19x its share: it is cut too
    assert!(
        last.bodies.iter().all(|b| b.parts.is_some()),
        "the sphere and the plate split"
    );
    for body in &last.bodies {
        let cells = body.parts.as_ref().unwrap();
        let n = body.tris.len() + body.quads.len();
        assert_eq!((cells.part.len(), cells.worker.len()), (n, n));
        assert_eq!(
            cells.part.iter().copied().collect::<BTreeSet<u32>>(),
            BTreeSet::from([0, 1])
        );
        let mut worker_of_part = [BTreeSet::new(), BTreeSet::new()];
        for (&q, &w) in cells.part.iter().zip(&cells.worker) {
            worker_of_part[q as usize].insert(w);
        }
        assert!(
            worker_of_part.iter().all(|w| w.len() == 1),
            "{worker_of_part:?}"
        );
        assert_ne!(worker_of_part[0], worker_of_part[1]);
        // RCB by cost halves each body's elements (one kind each: equal weights)
        let in0 = cells.part.iter().filter(|&&q| q == 0).count();
        assert!(in0.abs_diff(n - in0) <= 1, "parts of {in0} and {}", n - in0);
        // part 0 on the group's home
        let home = body.placement.unwrap().worker;
        assert!(worker_of_part[0].contains(&home), "home {home}");
    }
}
