//! Frames of split groups from their parts (protocol v19): every holder sends its
//! parts' shares and the master scatters them into each body's frame, with no
//! assembly of whole bodies. Every frame (positions, velocities, rotations, contact
//! forces, membrane forces, bending moments, stresses) is one process's, bit for bit,
//! in process and over gRPC worker processes.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_io::FrameBody;
use crash_master::{CostModel, MasterError, RunOptions, RunStats, Sink, SinkError, SplitMode};
use crash_tests::procs::{master, out_dir, worker};
use crash_tests::runs::{input_of, run_local};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Keeps every frame's bodies (without where they were computed).
#[derive(Default)]
struct Frames {
    frames: Vec<(u64, Vec<FrameBody>)>,
}

impl Sink for Frames {
    fn energy(&mut self, _: u64, _: f64, _: &crash_core::EnergyTotals) -> Result<(), SinkError> {
        Ok(())
    }
    fn frame_begin(&mut self, step: u64, _: f64) -> Result<(), SinkError> {
        self.frames.push((step, Vec::new()));
        Ok(())
    }
    fn frame_body(&mut self, mut body: FrameBody) -> Result<(), SinkError> {
        body.complete();
        (body.placement, body.parts) = (None, None);
        if let Some(f) = self.frames.last_mut() {
            f.1.push(body);
        }
        Ok(())
    }
    fn frame_end(&mut self) -> Result<(), SinkError> {
        Ok(())
    }
    fn finish(&mut self, _: &RunStats, _: Option<&MasterError>) -> Result<(), SinkError> {
        Ok(())
    }
}

fn scene_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
}

/// The frames of `rel` to `end` with frames every `every` seconds over `workers`
/// in-process workers with `split`, and the number of splits made.
fn frames(rel: &str, end: f64, every: f64, workers: usize, split: SplitMode) -> (Frames, u64) {
    let mut inp = input_of(&scene_path(rel));
    inp.config.end_time = end;
    inp.output_interval = every;
    let opts = RunOptions {
        cost: CostModel::Estimated,
        split,
        ..RunOptions::default()
    };
    let mut sink = Frames::default();
    let stats = run_local(inp, workers, &mut sink, &opts).unwrap();
    (sink, stats.splits)
}

/// Every frame equal, body by body (the first that differs named).
fn assert_same_frames(got: &Frames, want: &Frames) {
    assert_eq!(got.frames.len(), want.frames.len(), "frame count");
    for ((sg, bg), (sw, bw)) in got.frames.iter().zip(&want.frames) {
        assert_eq!(sg, sw, "frame steps");
        assert_eq!(bg.len(), bw.len(), "bodies in the frame of step {sg}");
        for (g, w) in bg.iter().zip(bw) {
            assert!(g == w, "frame of step {sg}: body {} differs", g.id);
        }
    }
}

#[test]
fn frames_of_a_split_group_from_its_parts_are_one_processs_bit_for_bit() {
    // the showcase split over two workers (after the first split frame, every frame
    // from the parts), and many spheres on one deformable plate over three
    for (rel, end, every, workers) in [
        ("scenes/sphere-on-plate.toml", 4e-4, 5e-5, 2),
        (
            "scenes/bench/spheres-on-deformable-plate.toml",
            1.5e-4,
            3e-5,
            3,
        ),
    ] {
        let (split, splits) = frames(rel, end, every, workers, SplitMode::Auto);
        assert!(splits >= 1, "{rel}: the group must be split");
        let (one, _) = frames(rel, end, every, 1, SplitMode::Off);
        assert!(one.frames.len() >= 5, "{rel}: {} frames", one.frames.len());
        assert_same_frames(&split, &one);
    }
}

/// Over `crash-worker` processes: the frame files of a split run are those of one
/// process but for the cells that say where each element was computed.
#[test]
fn frame_files_of_a_split_run_over_grpc_workers_hold_one_processs_values() {
    let p = scene_path("scenes/sphere-on-plate.toml");
    let out = out_dir("split-frames-grpc");
    let extra = [
        "--split",
        "auto",
        "--end-time",
        "3e-4",
        "--output-interval",
        "5e-5",
    ];
    let (mut m, url) = master(&p, 2, &out, &extra);
    let mut w: Vec<_> = (0..2).map(|_| worker(&url, 1, &[])).collect();
    assert!(m.wait(Duration::from_secs(600)).success(), "{}", m.log());
    for p in &mut w {
        assert!(p.wait(Duration::from_secs(30)).success(), "{}", p.log());
    }
    let (one, _) = frames("scenes/sphere-on-plate.toml", 3e-4, 5e-5, 1, SplitMode::Off);
    let got = read_frames(&out.join("frames"));
    assert_eq!(got.len(), one.frames.len(), "frame files");
    for (k, (f, (_, want))) in got.iter().zip(&one.frames).enumerate() {
        let g: Vec<FrameBody> = f
            .bodies
            .iter()
            .cloned()
            .map(|mut b| {
                (b.placement, b.parts) = (None, None);
                b
            })
            .collect();
        // the file holds what the run wrote: the one-process frame through the same format
        assert_eq!(g.len(), want.len(), "bodies in frame file {k}");
        for (a, b) in g.iter().zip(want) {
            // (a frame file holds no rotations)
            let same = [
                ("positions", a.x == b.x),
                ("velocities", a.v == b.v),
                ("contact forces", a.f_contact == b.f_contact),
                ("bending moments", a.m == b.m),
                ("membrane forces", a.n == b.n),
                ("stresses", a.von_mises_top == b.von_mises_top),
                ("stresses", a.von_mises_bottom == b.von_mises_bottom),
            ];
            for (what, ok) in same {
                assert!(ok, "frame file {k}, body {}: {what} differ", a.id);
            }
        }
    }
    assert!(
        m.log().contains("split over workers"),
        "the showcase must be split: {}",
        m.log()
    );
}

fn read_frames(dir: &Path) -> Vec<crash_io::Frame> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "vtu"))
        .collect();
    paths.sort();
    paths
        .iter()
        .map(|p| crash_io::read_vtu(p).unwrap())
        .collect()
}
