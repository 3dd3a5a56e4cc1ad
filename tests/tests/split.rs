//! Groups split over workers by elements (issue 16 point 2): the master loop over
//! in-process workers with a group cut into parts on several workers gives the state
//! hash of the single-process core driver, bit for bit (the showcase, many spheres on one
//! deformable plate, and a scene whose groups change, so split groups are merged back
//! and split again), and the contact statistics (contacts.csv) of one worker.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_core::contact::SegmentSides;
use crash_master::{CostModel, RecordSink, RunInput, RunOptions, SplitMode};
use crash_tests::procs::{master, out_dir, worker};
use crash_tests::runs::{contact_rows, driver_reference, input, input_of, resume_local, run_local};
use std::path::PathBuf;
use std::time::Duration;

fn opts(split: SplitMode) -> RunOptions {
    RunOptions {
        cost: CostModel::Estimated,
        split,
        ..RunOptions::default()
    }
}

fn scene(rel: &str, end: f64) -> RunInput {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel);
    let mut inp = input_of(&p);
    inp.config.end_time = end;
    inp
}

/// The final state hash over `workers` in-process workers with `split`, and how many
/// splits were made. Its contact statistics are one worker's, bit for bit: each push
/// booked once, by the holder owning its slave node, the sums exact.
fn split_run(inp: &RunInput, workers: usize, split: SplitMode) -> (u64, u64) {
    let mut sink = RecordSink::default();
    let stats = run_local(inp.clone(), workers, &mut sink, &opts(split)).unwrap();
    assert_eq!(Some(stats.final_hash), sink.last_hash);
    let mut one = RecordSink::default();
    run_local(inp.clone(), 1, &mut one, &opts(SplitMode::Off)).unwrap();
    let (got, want) = (contact_rows(&sink), contact_rows(&one));
    assert!(!want.is_empty(), "no contact in the scene");
    let first = (0..want.len().max(got.len())).find(|&k| got.get(k) != want.get(k));
    assert_eq!(
        first, None,
        "first contacts.csv row that differs from one worker's"
    );
    (stats.final_hash, stats.splits)
}

#[test]
fn the_showcase_split_over_two_workers_has_the_single_process_state() {
    let inp = scene("scenes/sphere-on-plate.toml", 1.2e-3);
    let (_, reference) = driver_reference(&inp);
    assert_eq!(format!("{reference:016x}"), "1370e0b4b94fd75d");
    let (hash, splits) = split_run(&inp, 2, SplitMode::Auto);
    assert!(splits >= 1, "the showcase's one group must be split");
    assert_eq!(format!("{hash:016x}"), format!("{reference:016x}"));
}

/// `crash-master --split auto` over 2 `crash-worker` processes (gRPC on loopback):
/// the showcase to 1.2 ms ends in the single-process state, and the log names the split.
#[test]
fn the_showcase_split_over_two_grpc_workers_has_the_single_process_state() {
    let s = grpc_split("scenes/sphere-on-plate.toml", "split-grpc", SHOWCASE_SPLIT);
    assert_eq!(s.final_state_hash, "1370e0b4b94fd75d");
}

/// `crash-master` with `extra` over 2 `crash-worker` processes on scene `rel` (into
/// out dir `name`): the log names a split over both workers, the run ends without a
/// fault; its summary.
fn grpc_split(rel: &str, name: &str, extra: &[&str]) -> crash_io::Summary {
    let out = out_dir(name);
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel);
    let (mut m, url) = master(&p, 2, &out, extra);
    let mut w: Vec<_> = (0..2).map(|_| worker(&url, 1, &[])).collect();
    assert!(m.wait(Duration::from_secs(600)).success(), "{}", m.log());
    for p in &mut w {
        assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    }
    assert!(
        m.log().contains("split over workers [0, 1]")
            || m.log().contains("split over workers [1, 0]"),
        "{}",
        m.log()
    );
    let s = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).unwrap();
    assert!(s.fault.is_none(), "{:?}", s.fault);
    s
}

/// The showcase's split run over gRPC workers: to 1.2 ms, a frame at half time.
const SHOWCASE_SPLIT: &[&str] = &[
    "--split",
    "auto",
    "--end-time",
    "1.2e-3",
    "--output-interval",
    "6e-4",
];

/// The showcase under the segment pass (`contact.pass = "segments"`) to 1.2 ms.
const SEGMENTS: &str = "scenes/bench/sphere-on-plate-segments.toml";
const SEGMENTS_HASH: &str = "e116e75428ba1063";

/// Under the segment pass the split group's views reach its points' masters and the
/// normals' neighbours, and its contact pass runs in the step (its stiffening step
/// limits the next one): the single-process state and one worker's contacts.csv.
#[test]
fn the_showcase_under_the_segment_pass_split_over_two_workers_has_the_single_process_state() {
    let inp = scene(SEGMENTS, 1.2e-3);
    let (_, reference) = driver_reference(&inp);
    assert_eq!(format!("{reference:016x}"), SEGMENTS_HASH);
    let (hash, splits) = split_run(&inp, 2, SplitMode::Auto);
    assert!(splits >= 1, "the showcase's one group must be split");
    assert_eq!(format!("{hash:016x}"), SEGMENTS_HASH);
}

/// Both sides (`contact.sides = "both"`: each body's points against the other at half
/// the weight) is the segment pass as it ran before session 40, bit for bit (that
/// pass's hash), and split over two workers it keeps the single-process state.
#[test]
fn under_both_sides_the_segment_pass_is_the_two_sided_pass_of_before_in_every_mode() {
    let mut inp = scene(SEGMENTS, 1.2e-3);
    inp.contact.sides = SegmentSides::Both;
    let (_, reference) = driver_reference(&inp);
    assert_eq!(format!("{reference:016x}"), "07508666adfac5f1");
    let (hash, splits) = split_run(&inp, 2, SplitMode::Auto);
    assert!(splits >= 1, "the showcase's one group must be split");
    assert_eq!(format!("{hash:016x}"), "07508666adfac5f1");
}

/// The same over 2 `crash-worker` processes (gRPC on loopback).
#[test]
fn the_showcase_under_the_segment_pass_split_over_two_grpc_workers_has_the_single_process_state() {
    let s = grpc_split(SEGMENTS, "split-grpc-segments", SHOWCASE_SPLIT);
    assert_eq!(s.final_state_hash, SEGMENTS_HASH);
}

/// Two coarse spheres head-on under the segment pass, split over two workers (every
/// body cut): the stiffening step halves the clock while they press (dt 1.33 to 3.04
/// us), each holder reports it for the points it counts and the master takes the
/// minimum, in process and over gRPC: the single-process state. One mesh on both
/// spheres: the default `auto` sides run both ways, the bits of the two-sided pass
/// before session 40 (one side gave ea79e176fdb34eec).
#[test]
fn the_segment_pass_stiffening_step_over_split_workers_keeps_the_single_process_state() {
    let rel = "tests/scenes/coarse-spheres-segments.toml";
    let inp = scene(rel, 1.5e-3);
    let (_, reference) = driver_reference(&inp);
    let want = "f375c896d40286be";
    assert_eq!(format!("{reference:016x}"), want);
    let (hash, splits) = split_run(&inp, 2, SplitMode::Always);
    assert!(splits >= 1);
    assert_eq!(format!("{hash:016x}"), want);
    let s = grpc_split(rel, "split-grpc-stiffening", &["--split", "always"]);
    assert!(
        s.dt_min_s < 0.5 * s.dt_max_s,
        "{} {}",
        s.dt_min_s,
        s.dt_max_s
    );
    assert_eq!(s.final_state_hash, want);
}

#[test]
fn many_spheres_on_one_plate_split_over_two_workers_have_the_single_process_state() {
    let inp = scene("scenes/bench/spheres-on-deformable-plate.toml", 3e-4);
    let (_, reference) = driver_reference(&inp);
    let (hash, splits) = split_run(&inp, 2, SplitMode::Auto);
    assert!(splits >= 1, "the one group of 65 bodies must be split");
    assert_eq!(format!("{hash:016x}"), format!("{reference:016x}"));
}

#[test]
fn groups_split_merged_back_and_split_again_keep_the_single_process_state() {
    let inp = input("ten-spheres-tiny.toml");
    let (_, reference) = driver_reference(&inp);
    split_again_and_resume(&inp, reference, &[2, 3]);
}

/// `inp` split always over each count of `workers` (cut at least twice over 2 or
/// more), then over 2 with a checkpoint every 7 steps (each assembles the split bodies
/// at their homes) and resumed from the middle one (split again): every final state
/// `reference`.
fn split_again_and_resume(inp: &RunInput, reference: u64, workers: &[usize]) {
    for &n in workers {
        let (hash, splits) = split_run(inp, n, SplitMode::Always);
        assert!(n < 2 || splits >= 2, "{n} workers: {splits} splits");
        assert_eq!(hash, reference, "{n} workers");
    }
    let mut sink = RecordSink::default();
    let o = RunOptions {
        checkpoint_every: 7,
        ..opts(SplitMode::Always)
    };
    let stats = run_local(inp.clone(), 2, &mut sink, &o).unwrap();
    assert!(stats.splits >= 2);
    assert!(!sink.checkpoints.is_empty(), "no checkpoint taken");
    assert_eq!(stats.final_hash, reference, "with checkpoints");
    // a checkpoint assembled from parts is complete: resumed (split again), the run
    // ends in the same state
    let ck = sink.checkpoints[sink.checkpoints.len() / 2].clone();
    let mut again = RecordSink::default();
    let resumed = resume_local(inp.clone(), ck, 2, &mut again, &opts(SplitMode::Always)).unwrap();
    assert_eq!(
        resumed.final_hash, reference,
        "resumed from a split run's checkpoint"
    );
}

/// Force slots carried as node sums (`crash_core::summed`), forced for every whole body
/// in this process: wholes that ran summed are split into parts (which gather every
/// slot), parts are assembled back into wholes, checkpoints taken and resumed; the
/// single-process state of the gathered slots. Forcing the mode while the other tests
/// of this file run changes none of their results: the same bits is the invariant.
#[test]
fn summed_force_slots_split_merged_back_and_split_again_keep_the_single_process_state() {
    let inp = input("ten-spheres-tiny.toml");
    let (_, reference) = driver_reference(&inp);
    crash_core::summed::set_summed_slots(Some(true));
    split_again_and_resume(&inp, reference, &[1, 2, 3]);
    crash_core::summed::set_summed_slots(None);
}

/// Bodies that leave a split group (spheres bouncing off the floor) leave the split as
/// it is: no merge back and cut again while every MEIM group lies within the groups
/// the workers hold; the state is still the single-process one.
#[test]
fn bodies_leaving_a_split_group_keep_the_split_and_the_single_process_state() {
    let inp = scene("scenes/bench/spheres-on-deformable-plate.toml", 1e-3);
    let (_, reference) = driver_reference(&inp);
    let mut sink = RecordSink::default();
    let stats = run_local(inp, 2, &mut sink, &opts(SplitMode::Auto)).unwrap();
    assert!(stats.splits_kept >= 1, "no group change kept the split");
    assert_eq!(stats.splits, 1, "the split was cut again");
    // groups.csv's rows: every group is timed, also the bodies that left the split and
    // are computed with it (each row: its holder's time for the split's parts)
    let (_, _, rows) = sink.groups.last().unwrap();
    assert!(
        rows.iter().filter(|r| r.bodies.len() == 1).count() >= 1,
        "no body out of the split's largest group: {rows:?}"
    );
    assert!(
        rows.iter().all(|r| r.step_ns > 0),
        "a group without its step time: {rows:?}"
    );
    assert_eq!(
        format!("{:016x}", stats.final_hash),
        format!("{reference:016x}")
    );
}

/// A physical fault found by a part (tunnelling: the largest move over the parts, its
/// node named in the whole body) stops the run with exactly the driver's fault.
#[test]
fn a_fault_in_a_split_group_is_the_drivers_fault() {
    let text = std::fs::read_to_string(crash_tests::fixtures::test_scene("two-spheres-tiny.toml"))
        .unwrap()
        .replace(
            "penalty_scale = 0.1",
            "penalty_scale = 0.1\nmargin = 1.0e-5",
        )
        .replace("velocity = [5.0, 0.0, 0.0]", "velocity = [400.0, 0.0, 0.0]");
    let scene = crash_scene::parse(&text, "fast.toml").unwrap();
    let inp = RunInput::from_built(scene.build().unwrap());
    let mut g = crash_core::Group::new(inp.bodies.all().unwrap(), inp.gravity);
    g.contact = inp.contact;
    let expected = crash_core::driver::Run::new(g, inp.config)
        .unwrap()
        .run(|_| {})
        .unwrap_err();
    assert!(
        matches!(expected, crash_core::Fault::Tunnelling { .. }),
        "{expected}"
    );
    let mut sink = RecordSink::default();
    let err = run_local(inp, 2, &mut sink, &opts(SplitMode::Always)).unwrap_err();
    match &err {
        crash_master::MasterError::Fault(f) => assert_eq!(f, &expected),
        other => panic!("{other}"),
    }
}

/// Nothing computed is lost at a fault: a split group's contact rows of step n wait for
/// its pass, which runs at the start of step n + 1. When a later exchange faults, the
/// rows of every step before the fault are written as one worker writes them: the two
/// spheres in contact from the start, then `extra` (TOML appended to the scene, whose
/// last body is the right sphere). Returns the fault.
fn rows_kept_at_fault(extra: &str) -> crash_core::Fault {
    let text = crash_tests::fixtures::spheres_in_contact(extra);
    let scene = crash_scene::parse(&text, "pushed.toml").unwrap();
    let inp = RunInput::from_built(scene.build().unwrap());
    let mut one = RecordSink::default();
    let expected = match run_local(inp.clone(), 1, &mut one, &opts(SplitMode::Off)).unwrap_err() {
        crash_master::MasterError::Fault(f) => f,
        other => panic!("{other}"),
    };
    let mut sink = RecordSink::default();
    match run_local(inp, 2, &mut sink, &opts(SplitMode::Always)).unwrap_err() {
        crash_master::MasterError::Fault(f) => assert_eq!(f, expected),
        other => panic!("{other}"),
    }
    let steps = |s: &RecordSink| s.contact_stats.iter().map(|r| r.0).collect::<Vec<_>>();
    // in contact from the first step to the last one before the fault
    let last = steps(&one).last().copied();
    assert_eq!(
        steps(&one),
        (1..=last.unwrap_or(0)).collect::<Vec<_>>(),
        "{expected}"
    );
    assert_eq!(steps(&sink), steps(&one), "contact rows lost at the fault");
    assert_eq!(contact_rows(&sink), contact_rows(&one));
    expected
}

/// A load of `force` newtons along x on every node of the right sphere from 0.1 ms.
fn pull_right(force: &str) -> String {
    crash_tests::fixtures::pull_last(force)
}

/// The fault in the exchange after the one that ran the pass: the right sphere, pulled
/// off the left one, outruns the contact margin, found when the parts' moves meet (the
/// Halo exchange).
#[test]
fn a_fault_after_a_split_groups_contact_pass_keeps_the_rows_of_every_step_before() {
    let f = rows_kept_at_fault(&pull_right("1.0e5"));
    assert!(
        matches!(f, crash_core::Fault::Tunnelling { step, .. } if step > 20),
        "{f}"
    );
}

/// The fault in the exchange that runs the pass (a Step): a load beyond any finite
/// acceleration gives the right sphere non-finite velocities in its parts'
/// integration; the holders' shares of the pass come back with the fault and the
/// other's report.
#[test]
fn a_fault_in_the_step_that_runs_a_split_groups_contact_pass_keeps_the_rows_before() {
    let f = rows_kept_at_fault(&pull_right("1.0e308"));
    assert!(
        matches!(f, crash_core::Fault::NonFinite { body: 1, step, .. } if step > 20),
        "{f}"
    );
}

/// The fault in a whole group in the Step that runs the split group's pass: a third
/// sphere resting on a fixed plate (a group with a read-only copy, never split) is
/// pushed beyond any finite acceleration; the worker runs its split groups' pending
/// passes before it answers with the fault. The plate lies 1.005 mm below the sphere
/// (1 mm of thickness between them): close enough to pair them from the start, so the
/// sphere's group holds the plate's copy and stays whole (it names the driver's node).
#[test]
fn a_fault_in_a_whole_group_keeps_the_split_groups_rows_before() {
    let f = rows_kept_at_fault(&crash_tests::fixtures::third_sphere_on_a_plate());
    assert!(
        matches!(f, crash_core::Fault::NonFinite { body: 2, step, .. } if step > 20),
        "{f}"
    );
}

/// A body split into parts over two workers names the non-finite node one process
/// names (the lowest of the whole body): every part is stepped and the first fault in
/// `Fault::order` kept, on each holder and over the holders. Here a third sphere, alone
/// and so split too, is pushed beyond any finite acceleration: every node goes
/// non-finite at once, so the name shows the rule (node 0; the part that found its
/// fault first named node 19 before).
#[test]
fn a_split_body_names_the_non_finite_node_one_process_names() {
    let f = rows_kept_at_fault(&crash_tests::fixtures::third_sphere());
    assert!(
        matches!(&f, crash_core::Fault::NonFinite { body: 2, place, .. } if place == "node 0"),
        "{f}"
    );
}

/// A sink that checks the order of the contact rows against the checkpoints: one
/// `contact_stats` call per step, in step order, and every checkpoint handed over
/// after its step's rows (a split group's rows wait for its pending contact pass:
/// crash-master `master/held.rs`).
#[derive(Default)]
struct RowOrder {
    inner: RecordSink,
    last: Option<u64>,
    checked: usize,
}

impl crash_master::Sink for RowOrder {
    fn energy(
        &mut self,
        step: u64,
        time: f64,
        totals: &crash_core::EnergyTotals,
    ) -> Result<(), crash_master::SinkError> {
        self.inner.energy(step, time, totals)
    }
    fn contact_stats(
        &mut self,
        step: u64,
        time: f64,
        stats: &[crash_core::contact::PairStats],
    ) -> Result<(), crash_master::SinkError> {
        let want = self.last.map_or(0, |s| s + 1);
        assert_eq!(step, want, "contact rows out of step order");
        self.last = Some(step);
        self.inner.contact_stats(step, time, stats)
    }
    fn checkpoint(
        &mut self,
        state: &crash_master::MasterCheckpoint,
    ) -> Result<(), crash_master::SinkError> {
        assert_eq!(
            self.last,
            Some(state.clock.step),
            "a checkpoint before its step's contact rows"
        );
        self.checked += 1;
        self.inner.checkpoint(state)
    }
    fn frame_begin(&mut self, step: u64, time: f64) -> Result<(), crash_master::SinkError> {
        self.inner.frame_begin(step, time)
    }
    fn frame_body(&mut self, body: crash_io::FrameBody) -> Result<(), crash_master::SinkError> {
        self.inner.frame_body(body)
    }
    fn frame_end(&mut self) -> Result<(), crash_master::SinkError> {
        self.inner.frame_end()
    }
    fn finish(
        &mut self,
        stats: &crash_master::RunStats,
        error: Option<&crash_master::MasterError>,
    ) -> Result<(), crash_master::SinkError> {
        self.inner.finish(stats, error)
    }
}

#[test]
fn split_groups_write_their_contact_rows_once_per_step_in_order_before_each_checkpoint() {
    let inp = input("ten-spheres-tiny.toml");
    let o = RunOptions {
        checkpoint_every: 7,
        ..opts(SplitMode::Always)
    };
    let mut sink = RowOrder::default();
    let stats = run_local(inp.clone(), 2, &mut sink, &o).unwrap();
    assert!(stats.splits >= 2, "{} splits", stats.splits);
    assert!(sink.checked >= 2, "{} checkpoints", sink.checked);
    assert_eq!(sink.last, Some(stats.steps), "the last step's rows");
    // and they are one worker's rows
    let mut one = RecordSink::default();
    run_local(inp, 1, &mut one, &opts(SplitMode::Off)).unwrap();
    assert!(contact_rows(&sink.inner) == contact_rows(&one));
}

/// The bodies of the two-sphere cluster scene and its setup.
fn two_spheres() -> (Vec<crash_core::Body>, crash_link::Setup) {
    let b = crash_scene::load(&crash_tests::fixtures::test_scene("two-spheres-tiny.toml"))
        .unwrap()
        .build()
        .unwrap();
    let setup = crash_link::Setup {
        gravity: b.gravity,
        contact: b.contact,
        reactions: false,
        probes: Default::default(),
    };
    (b.bodies, setup)
}

/// An engine loaded with bodies `ids` of the two spheres as one group, started at the
/// clock's origin.
fn started_with(ids: &[u32]) -> crash_worker::Engine {
    use crash_link::{BodyLoad, Command, Reply};
    let (bodies, setup) = two_spheres();
    let mut e = crash_worker::Engine::new();
    e.handle(Command::Setup(setup));
    let bodies = bodies.into_iter().filter(|x| ids.contains(&x.def.id));
    e.handle(Command::Load {
        at: crash_core::Clock::default(),
        bodies: bodies.map(BodyLoad::whole).collect(),
    });
    e.handle(Command::Regroup {
        groups: vec![ids.to_vec()],
        copies: Vec::new(),
    });
    assert!(matches!(e.handle(Command::Start), Reply::Report(_)));
    e
}

/// The worker answers a Split before it builds its own parts (they are built while the
/// master relays the bodies): a build that then fails is not lost. Every later command
/// is refused with its reason until a Reset (a rollback), which clears it.
#[test]
fn a_split_whose_own_parts_cannot_be_built_refuses_every_command_until_a_reset() {
    use crash_link::{BodyLoad, Command, Reply, SplitSpec};
    let mut e = started_with(&[0, 1]);
    // sphere 0 (320 triangles) cut into 400 parts: the columns fit, the cut cannot be made
    let k = 400u32;
    let spec = SplitSpec {
        ids: vec![0, 1],
        parts: vec![k, 1],
        holder: vec![(0..k).map(|q| q % 2).collect(), vec![1]],
        slot: 0,
        workers: vec![0, 1],
        peers: Vec::new(),
    };
    assert!(matches!(e.handle(Command::Split(spec)), Reply::Unloaded(ref v) if v.len() == 2));
    e.settle();
    for cmd in [
        Command::Frame(vec![0]),
        Command::States(vec![1]),
        Command::Start,
    ] {
        match e.handle(cmd) {
            Reply::Error(why) => assert!(why.contains("400 parts"), "{why}"),
            other => panic!("not refused: {other:?}"),
        }
    }
    assert!(matches!(e.handle(Command::Reset), Reply::Ack));
    let (bodies, _) = two_spheres();
    e.handle(Command::Load {
        at: crash_core::Clock::default(),
        bodies: bodies.into_iter().map(BodyLoad::whole).collect(),
    });
    e.handle(Command::Regroup {
        groups: vec![vec![0, 1]],
        copies: Vec::new(),
    });
    assert!(matches!(e.handle(Command::Start), Reply::Report(_)));
}

/// A split planned at the start (protocol v20): every holder was loaded with the group
/// and started it, so `Share` carries no bodies and each holder splits the group it
/// holds (slot 0 keeps answering for the bodies). A worker that does not hold that
/// group, or holds it at another clock, refuses.
#[test]
fn a_share_without_bodies_splits_the_group_held_here_and_nowhere_else() {
    use crash_core::Clock;
    use crash_link::{Command, Reply, SplitSpec};
    let share = |slot: u32, at: Clock| Command::Share {
        at,
        spec: SplitSpec {
            ids: vec![0, 1],
            parts: vec![2, 1],
            holder: vec![vec![0, 1], vec![1]],
            slot,
            workers: vec![0, 1],
            peers: Vec::new(),
        },
        bodies: Vec::new(),
    };
    let at = Clock::default();
    for slot in [0, 1] {
        let mut e = started_with(&[0, 1]);
        assert!(
            matches!(e.handle(share(slot, at)), Reply::Ack),
            "slot {slot}"
        );
        // the home answers for the whole bodies, the other holder for none
        assert_eq!(e.body_count(), if slot == 0 { 2 } else { 0 });
    }
    match started_with(&[1]).handle(share(1, at)) {
        Reply::Error(why) => assert!(why.contains("no group"), "{why}"),
        other => panic!("not refused: {other:?}"),
    }
    match started_with(&[0, 1]).handle(share(1, at.after(1e-7))) {
        Reply::Error(_) => {}
        other => panic!("a Share of another clock was taken: {other:?}"),
    }
}
