//! Kinematic bodies (every degree of freedom prescribed: the three plates of the ten
//! spheres) never join groups: each sphere that touches a plate stays its own group
//! with a read-only copy of the plate. Results stay those of the single-group driver
//! (tests/local.rs, modes.rs, cluster.rs check the bits); here: the grouping itself and
//! what users see of it (groups.csv, summary.json, the frames' worker and group fields).
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_master::{CostModel, RecordSink, RunOptions};
use crash_tests::fixtures::test_scene;
use crash_tests::runs::{input, run_local};
use std::collections::{BTreeMap, BTreeSet};

const SCENE: &str = "ten-spheres-tiny.toml";

#[test]
fn groups_never_contain_a_kinematic_touch_as_a_link_between_two_bodies() {
    let inp = input(SCENE);
    let kinematic: BTreeSet<String> = inp
        .briefs
        .iter()
        .filter(|b| b.kinematic)
        .map(|b| b.name.clone())
        .collect();
    let id_of: BTreeMap<String, u32> = inp.briefs.iter().map(|b| (b.name.clone(), b.id)).collect();
    assert_eq!(kinematic.len(), 3);
    let mut sink = RecordSink::default();
    let opts = RunOptions {
        cost: CostModel::Estimated,
        ..RunOptions::default()
    };
    let stats = run_local(inp, 2, &mut sink, &opts).unwrap();
    assert!(!sink.groups.is_empty());
    // MEIM edges in force at each step (the sink gets them whenever they change)
    let edges_at = |step: u64| -> Vec<(u32, u32)> {
        sink.contacts
            .iter()
            .rev()
            .find(|(s, _)| *s <= step)
            .map(|(_, e)| e.clone())
            .unwrap_or_default()
    };
    let kin_ids: BTreeSet<u32> = kinematic.iter().map(|n| id_of[n]).collect();
    let mut plate_touches = 0;
    for (step, _, rows) in &sink.groups {
        let edges = edges_at(*step);
        plate_touches += edges
            .iter()
            .filter(|(a, b)| kin_ids.contains(a) != kin_ids.contains(b))
            .count();
        for r in rows {
            let ids: Vec<u32> = r.bodies.iter().map(|n| id_of[n]).collect();
            if ids.iter().any(|id| kin_ids.contains(id)) {
                assert_eq!(
                    ids.len(),
                    1,
                    "step {step}: a kinematic body in group {ids:?}"
                );
                continue;
            }
            // the members are connected by edges between deformable bodies alone
            let mut reached = BTreeSet::from([ids[0]]);
            loop {
                let before = reached.len();
                for &(a, b) in &edges {
                    if reached.contains(&a) && ids.contains(&b) {
                        reached.insert(b);
                    }
                    if reached.contains(&b) && ids.contains(&a) {
                        reached.insert(a);
                    }
                }
                if reached.len() == before {
                    break;
                }
            }
            assert_eq!(reached.len(), ids.len(), "step {step}: group {ids:?}");
        }
    }
    assert!(plate_touches > 0, "no sphere came near a plate");
    // every body its own group but for spheres that touch each other
    assert!(stats.max_groups >= 10, "max groups {}", stats.max_groups);
}

/// `crash run --workers 2`: groups.csv's rows at the final time are the final groups
/// of summary.json, with their workers; the frames carry `worker` and `group` cells.
#[test]
fn groups_csv_is_consistent_with_summary_json() {
    let out = crash_tests::cli::crash_run(
        &test_scene(SCENE),
        "kinematic-groups-csv",
        &["--workers", "2"],
    );
    let summary = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    let c = &summary.cluster;
    assert_eq!(c.workers, 2);
    assert_eq!(c.compute_ns_per_worker.len(), 2);
    let text = std::fs::read_to_string(out.join("groups.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("time_s,group,bodies,worker,elements,step_ns")
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| {
            // time,group,"names",worker,elements,step_ns
            let (head, rest) = l.split_once(",\"").unwrap();
            let (names, tail) = rest.split_once("\",").unwrap();
            let mut v: Vec<String> = head.split(',').map(String::from).collect();
            v.push(names.to_string());
            v.extend(tail.split(',').map(String::from));
            v
        })
        .collect();
    let last_time = rows.last().unwrap()[0].clone();
    assert_eq!(last_time.parse::<f64>().unwrap(), summary.time_reached_s);
    let last: Vec<(u32, usize, usize)> = rows
        .iter()
        .filter(|r| r[0] == last_time)
        .map(|r| {
            (
                r[1].parse().unwrap(),
                r[2].split(' ').count(),
                r[3].parse().unwrap(),
            )
        })
        .collect();
    let expected: Vec<(u32, usize, usize)> = c
        .final_groups
        .iter()
        .map(|g| (g.group, g.bodies.len(), g.worker))
        .collect();
    assert_eq!(last, expected);
    // rows at time 0 and at every change: as many group changes as distinct times
    // beyond the output times
    let times: BTreeSet<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    assert!(times.len() as u64 >= c.group_changes.min(1));
    let frames = std::fs::read_dir(out.join("frames")).unwrap();
    let vtu = frames
        .filter_map(|e| e.ok())
        .find(|e| e.path().extension().is_some_and(|x| x == "vtu"))
        .unwrap();
    // the header is XML; the arrays after it are binary (appended raw data)
    let bytes = std::fs::read(vtu.path()).unwrap();
    let frame = String::from_utf8_lossy(&bytes);
    assert!(frame.contains(r#"Name="worker""#) && frame.contains(r#"Name="group""#));
    contact_forces_in_frames_cancel(&out.join("frames"));
}

/// Newton's third law in every frame: the nodal contact forces of all bodies sum to
/// zero (each push is +f on a node and -w_k f on segment nodes, sum w_k = 1), which
/// holds only if the forces on the kinematic plates, felt by read-only copies in the
/// spheres' groups on either worker, reach the plates' frames.
fn contact_forces_in_frames_cancel(dir: &std::path::Path) {
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "vtu"))
        .collect();
    paths.sort();
    let mut on_plates = 0;
    for p in &paths {
        let f = crash_io::read_vtu(p).unwrap();
        let (mut sum, mut scale) = (crash_core::Vec3::zeros(), 0.0f64);
        for b in &f.bodies {
            for fc in &b.f_contact {
                sum += fc;
                scale += fc.norm();
            }
            // the kinematic plates: lift, slide, tilt (the rest are balls)
            if !b.name.starts_with("ball") && b.f_contact.iter().any(|f| f.norm() > 0.0) {
                on_plates += 1;
            }
        }
        assert!(
            sum.norm() <= 1e-9 * scale.max(1e-300),
            "{}: contact forces sum to {sum:?} (total magnitude {scale:e})",
            p.display()
        );
    }
    assert!(on_plates > 0, "no frame shows contact force on a plate");
}

/// The figures of docs/architecture-cluster.md ("Kinematic bodies: the effect"):
/// `cargo test --release -p crash-tests --test kinematic -- --ignored --nocapture`.
/// Groups now, and the groups the old rule (kinematic bodies join groups) would have
/// formed from the same MEIM edges (the motion, hence the edges, is the same).
#[test]
#[ignore]
fn grouping_figures_of_ten_spheres_small() {
    let inp = crash_tests::runs::input_of(&crash_tests::fixtures::scene(
        "ten-spheres-three-plates-small.toml",
    ));
    let ids: Vec<u32> = inp.briefs.iter().map(|b| b.id).collect();
    let mut sink = RecordSink::default();
    let stats = run_local(inp, 2, &mut sink, &RunOptions::default()).unwrap();
    let old_rule = |edges: &[(u32, u32)]| -> usize {
        let mut parent: BTreeMap<u32, u32> = ids.iter().map(|&i| (i, i)).collect();
        fn find(p: &mut BTreeMap<u32, u32>, i: u32) -> u32 {
            let mut r = i;
            while p[&r] != r {
                r = p[&r];
            }
            r
        }
        for &(a, b) in edges {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            parent.insert(ra.max(rb), ra.min(rb));
        }
        let roots: BTreeSet<u32> = ids.iter().map(|&i| find(&mut parent, i)).collect();
        roots.len()
    };
    let (mut min_old, mut min_new) = (usize::MAX, usize::MAX);
    for (step, _, rows) in &sink.groups {
        let edges = sink
            .contacts
            .iter()
            .rev()
            .find(|(s, _)| s <= step)
            .map(|(_, e)| e.clone())
            .unwrap_or_default();
        min_old = min_old.min(old_rule(&edges));
        min_new = min_new.min(rows.len());
    }
    println!(
        "groups (fewest at once): old rule {min_old}, now {min_new}; max now {}",
        stats.max_groups
    );
    println!(
        "steps {}, group changes {}, migrations {}",
        stats.steps,
        stats.group_changes,
        stats.migrations.len()
    );
    println!("compute ns per worker {:?}", stats.worker_compute_ns);
    println!("final groups {:?}", stats.final_groups);
}
