//! What a user sees of a group split over workers (issue 16 point 5): each frame's
//! `worker` and `part` cells give, for every element of a split body, the part that
//! computes it and that part's worker. Invariants on the showcase split over 2
//! in-process workers (the sphere cut in 2, the plate whole): the sphere's elements
//! fall in parts 0 and 1, each part on one worker, the two on different workers, the
//! cut balanced; the plate is one part on one worker; the frames read back as written.
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
    let (split, whole): (Vec<_>, Vec<_>) = last.bodies.iter().partition(|b| b.parts.is_some());
    assert_eq!(
        (split.len(), whole.len()),
        (1, 1),
        "the sphere split, the plate whole"
    );
    let sphere = split[0];
    let cells = sphere.parts.as_ref().unwrap();
    let n = sphere.tris.len() + sphere.quads.len();
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
    // RCB by cost halves the sphere's elements (all triangles: equal weights)
    let in0 = cells.part.iter().filter(|&&q| q == 0).count();
    assert!(in0.abs_diff(n - in0) <= 1, "parts of {in0} and {}", n - in0);
    // the plate: whole, on the group's home, which computes part 0 of the sphere
    let plate = whole[0];
    let home = plate.placement.unwrap().worker;
    assert!(worker_of_part[0].contains(&home), "plate on worker {home}");

    // groups.csv and summary.json: the split group has one row per holder, whose
    // elements are the frame's cells on that worker and add up to the group's
    let summary = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    let text = std::fs::read_to_string(out.join("groups.csv")).unwrap();
    let last_time = text.lines().last().unwrap().split(',').next().unwrap();
    let rows: Vec<(String, usize, usize)> = text
        .lines()
        .skip(1)
        .filter(|l| l.split(',').next() == Some(last_time))
        .map(|l| {
            // time,group,"names",worker,elements,step_ns
            let (_, rest) = l.split_once(",\"").unwrap();
            let (names, tail) = rest.split_once("\",").unwrap();
            let t: Vec<&str> = tail.split(',').collect();
            (
                names.to_string(),
                t[0].parse().unwrap(),
                t[1].parse().unwrap(),
            )
        })
        .collect();
    assert_eq!(rows.len(), 2, "one row per holder: {rows:?}");
    let mut per_worker = std::collections::BTreeMap::new();
    for &w in &cells.worker {
        *per_worker.entry(w as usize).or_insert(0) += 1;
    }
    *per_worker.entry(home as usize).or_insert(0) += plate.tris.len() + plate.quads.len();
    for (names, worker, elements) in &rows {
        assert_eq!(per_worker.get(worker), Some(elements), "{rows:?}");
        let on_home = *worker == home as usize;
        assert_eq!(names.contains("plate"), on_home, "{rows:?}");
        assert!(names.contains("sphere"), "{rows:?}");
    }
    let groups = &summary.cluster.final_groups;
    assert_eq!(
        groups.iter().map(|g| g.worker).collect::<BTreeSet<_>>(),
        rows.iter().map(|r| r.1).collect::<BTreeSet<_>>(),
        "summary.json's final groups name the same holders"
    );
}
