//! The direct halo exchange (protocol v18): the holders of a group split over
//! `crash-worker` processes send each other their part states instead of through the
//! master. The same bits as one process, with 2 and 3 holders; a fault found in the
//! halo or in a holder's integration (whose peers are told to stop) ends the run as
//! one worker ends it, with the same contact rows; and a direct exchange that cannot
//! be made rolls the run back and relays, with the same final state.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_io::Summary;
use crash_master::RunInput;
use crash_tests::procs::{master, out_dir, worker};
use crash_tests::runs::driver_reference;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A finished cluster run: its summary, contacts.csv, the master's and the workers'
/// logs and whether it exited 0.
struct Ran {
    summary: Summary,
    contacts: String,
    log: String,
    workers: String,
    ok: bool,
}

fn cluster(
    name: &str,
    scene: &Path,
    workers: usize,
    master_extra: &[&str],
    worker_extra: &[&str],
) -> Ran {
    let out = out_dir(name);
    let (mut m, url) = master(scene, workers, &out, master_extra);
    let mut w: Vec<_> = (0..workers)
        .map(|_| worker(&url, 1, worker_extra))
        .collect();
    let ok = m.wait(Duration::from_secs(600)).success();
    for p in &mut w {
        p.wait(Duration::from_secs(60));
    }
    Ran {
        summary: crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap(),
        contacts: std::fs::read_to_string(out.join(crash_io::CONTACTS_CSV)).unwrap_or_default(),
        log: m.log(),
        workers: w.iter().map(|p| p.log()).collect::<Vec<_>>().join("\n"),
        ok,
    }
}

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
}

/// Groups split, merged back and split again over three worker processes, each
/// holder exchanging with two others directly: the single-process state.
#[test]
fn three_holders_exchanging_halos_directly_end_in_the_single_process_state() {
    let scene = crash_tests::fixtures::test_scene("ten-spheres-tiny.toml");
    let inp: RunInput = crash_tests::runs::input_of(&scene);
    let (_, reference) = driver_reference(&inp);
    let r = cluster("direct3", &scene, 3, &["--split", "always"], &[]);
    assert!(r.ok, "{}", r.log);
    assert!(r.summary.cluster.splits >= 2, "{:?}", r.summary.cluster);
    assert!(
        r.summary.cluster.halo_direct_steps > 0,
        "{:?}",
        r.summary.cluster
    );
    assert_eq!(r.summary.cluster.halo_relayed_steps, 0, "{}", r.log);
    assert_eq!(r.summary.final_state_hash, format!("{reference:016x}"));
}

/// The split fault tests' scene (two spheres in contact from the start, the right one
/// pulled with `force` newtons, then `more` bodies), written next to the runs.
fn pushed_scene(name: &str, force: &str, more: &str) -> PathBuf {
    let pull = crash_tests::fixtures::pull_last(force);
    let text = crash_tests::fixtures::spheres_in_contact(&(pull + more));
    let p = out_dir(name).join("pushed.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// The fault of a split run over worker processes exchanging halos directly is one
/// worker's fault, and the contact rows written up to it are one worker's, byte for
/// byte. Three workers: the master replays a reported fault on the others before it
/// believes it (docs/reliability.md), here split over the two left, directly again,
/// and the summary is the replay's. Returns the fault.
fn direct_fault_is_one_workers(name: &str, force: &str, more: &str) -> String {
    let scene = pushed_scene(name, force, more);
    let one = cluster(&format!("{name}-1"), &scene, 1, &[], &[]);
    let two = cluster(&format!("{name}-3"), &scene, 3, &["--split", "always"], &[]);
    assert!(!one.ok && !two.ok, "both runs must stop on the fault");
    let fault = one.summary.fault.clone().unwrap();
    assert_eq!(
        two.summary.fault.as_deref(),
        Some(fault.as_str()),
        "{}",
        two.log
    );
    // the summary of a failed run is the replay's checkpoint's: the log tells
    assert!(
        two.log.contains("the workers exchange its halos directly")
            && !two.log.contains("relays its halos"),
        "{}",
        two.log
    );
    // the holders were told of the stop: none waited for states that never came
    assert!(
        !two.workers
            .contains("direct halo exchange with the other holders failed"),
        "{}",
        two.workers
    );
    assert!(one.contacts.lines().count() > 20, "{}", one.contacts);
    assert_eq!(
        two.contacts, one.contacts,
        "contact rows lost or changed at the fault"
    );
    fault
}

/// Found in the halo (the parts' moves meet there): the right sphere, pulled off the
/// left one, outruns the contact margin.
#[test]
fn a_fault_found_in_a_direct_halo_is_one_workers_with_its_rows() {
    let f = direct_fault_is_one_workers("direct-tunnel", "1.0e5", "");
    assert!(f.contains("tunnel") || f.contains("margin"), "{f}");
}

/// Found in a holder's integration (non-finite velocities in every part of the pulled
/// sphere, so every holder faults).
#[test]
fn a_fault_in_every_holders_integration_is_one_workers() {
    let f = direct_fault_is_one_workers("direct-nonfinite", "1.0e308", "");
    assert!(f.contains("non-finite"), "{f}");
}

/// Found in one worker's whole group (a third sphere on a fixed plate, pushed beyond
/// any finite acceleration) while the split group steps fine: that worker tells the
/// other holders to stop instead of sending its part states (without, they would wait
/// out their `--peer-timeout` and log the failed exchange), and the run ends as one
/// worker's.
#[test]
fn a_fault_in_a_whole_group_stops_the_holders_peers_and_is_one_workers() {
    let f = direct_fault_is_one_workers(
        "direct-whole",
        "0.0",
        &crash_tests::fixtures::third_sphere_on_a_plate(),
    );
    assert!(f.contains("non-finite") && f.contains("body 2"), "{f}");
}

/// Workers that announce a host no peer can reach: the first split step's direct
/// exchange fails, the master goes back to its checkpoint (the start: the summary
/// counts the steps after it) and relays the part states from then on, and the run
/// ends in the state it ends in everywhere.
#[test]
fn a_direct_halo_that_cannot_connect_falls_back_to_the_relay_with_the_same_state() {
    let scene = repo("scenes/sphere-on-plate.toml");
    let r = cluster(
        "direct-fallback",
        &scene,
        2,
        &["--split", "auto", "--end-time", "3e-4"],
        &["--peer-host", "192.0.2.1", "--peer-timeout", "2"],
    );
    assert!(r.ok, "{}", r.log);
    assert!(
        r.log
            .contains("could not exchange halos with the other workers directly"),
        "{}",
        r.log
    );
    assert!(
        r.workers
            .contains("direct halo exchange with the other holders failed"),
        "{}",
        r.workers
    );
    assert!(
        r.summary.cluster.halo_relayed_steps > 100,
        "{:?}",
        r.summary.cluster
    );
    let mut inp = crash_tests::runs::input_of(&scene);
    inp.config.end_time = 3e-4;
    let (_, reference) = driver_reference(&inp);
    assert_eq!(r.summary.final_state_hash, format!("{reference:016x}"));
}
