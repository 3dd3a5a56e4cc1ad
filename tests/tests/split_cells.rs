//! What a user sees of a group split over workers (issue 16 point 5): each frame's
//! `worker` and `part` cells give, for every element of a split body, the part that
//! computes it and that part's worker. Invariants on the showcase split over 2
//! in-process workers (the sphere and the plate each cut in 2): each body's elements
//! fall in parts 0 and 1, each part on one worker, the two on different workers, the
//! cut balanced by what each part computes, part 0 on the group's home; the frames read back as written; groups.csv
//! and summary.json list the group once per holder with the elements computed there.
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
        // RCB balances what each part computes (crash-core `computed_costs`: a part
        // also computes the cut elements at the nodes it owns), so the elements each
        // is given differ by at most those on the cut (under 2 % of the body's here)
        let in0 = cells.part.iter().filter(|&&q| q == 0).count();
        assert!(
            in0.abs_diff(n - in0) <= n / 50,
            "parts of {in0} and {}",
            n - in0
        );
        // part 0 on the group's home
        let home = body.placement.unwrap().worker;
        assert!(worker_of_part[0].contains(&home), "home {home}");
    }

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
    for body in &last.bodies {
        for &w in &body.parts.as_ref().unwrap().worker {
            *per_worker.entry(w as usize).or_insert(0) += 1;
        }
    }
    for (names, worker, elements) in &rows {
        assert_eq!(per_worker.get(worker), Some(elements), "{rows:?}");
        assert_eq!(
            names, "plate sphere",
            "both bodies have parts on each holder"
        );
    }
    let groups = &summary.cluster.final_groups;
    assert_eq!(
        groups.iter().map(|g| g.worker).collect::<BTreeSet<_>>(),
        rows.iter().map(|r| r.1).collect::<BTreeSet<_>>(),
        "summary.json's final groups name the same holders"
    );
}
