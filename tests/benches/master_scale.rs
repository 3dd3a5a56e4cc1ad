//! The master's own cost per step with many workers and many bodies (issue 16, point 7;
//! docs/scaling.md). The workers are in-process links that answer at once: each keeps
//! the bodies it is given and answers a step with the reports of a rigid translation
//! (boxes moved by v dt, constant energies), so every nanosecond measured is the master's
//! (gathering the reports in body-id order, dt, the energy ledger, the margin check, the
//! level-i search and MEIM update, placement and migration) plus the trivial link.
//!
//! Bodies: `n` two-triangle plates (10 mm) on a square grid 11.5 mm apart, drifting with
//! velocities that bring neighbours within the contact margin now and then, so the MEIM
//! merges and splits groups and bodies migrate as in a real run.
//!
//! Run: cargo bench -p crash-tests --bench master_scale [-- BODIES STEPS]
#![allow(clippy::unwrap_used)]

use crash_core::contact::ContactConfig;
use crash_core::shapes::{plate, ElementKind};
use crash_core::{Body, BodyEnergy, BodyReport, Material, Section, Stabilization, Vec3};
use crash_core::{BodyBrief, RunConfig};
use crash_io::FrameBody;
use crash_link::{BodyLoad, Command, GroupTime, LinkError, Reply, StepReport, WorkerLink};
use crash_master::{run_with, BodySource, RecordSink, RunInput, RunOptions};
use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

const SPACING: f64 = 0.0115;
const SIZE: f64 = 0.01;

/// A body as the instant worker keeps it: its load (returned on Unload), its box and
/// its drift velocity.
struct Held {
    load: BodyLoad,
    lo: Vec3,
    hi: Vec3,
    v: Vec3,
    energy: BodyEnergy,
}

/// A worker that answers every command at once (no integration).
#[derive(Default)]
struct InstantWorker {
    held: BTreeMap<u32, Held>,
    groups: Vec<Vec<u32>>,
    defs: std::collections::BTreeSet<u32>,
    queue: VecDeque<Reply>,
}

impl InstantWorker {
    fn report(&mut self, dt: f64) -> StepReport {
        let mut bodies = Vec::with_capacity(self.held.len());
        for (&id, h) in self.held.iter_mut() {
            let d = h.v * dt;
            h.lo += d;
            h.hi += d;
            bodies.push(BodyReport {
                id,
                energy: h.energy,
                stable_dt: 1e-6,
                dt_element: 0,
                lo: h.lo,
                hi: h.hi,
                max_move: d.norm(),
                hot_element: 0,
                hot_density: 0.0,
                reaction: None,
            });
        }
        let groups = self
            .groups
            .iter()
            .filter_map(|g| g.first())
            .map(|&first| GroupTime { first, nanos: 1000 })
            .collect();
        StepReport {
            bodies,
            groups,
            compute_ns: 0,
            contacts: Vec::new(),
            codec_ns: 0,
            probes: Vec::new(),
            parts: Vec::new(),
            part_dts: Default::default(),
            split_contacts: Vec::new(),
            split_limits: Vec::new(),
            halo: None,
        }
    }

    fn answer(&mut self, cmd: Command) -> Reply {
        match cmd {
            Command::Setup(_) | Command::Shutdown(_) => Reply::Ack,
            Command::Load { bodies, .. } => {
                for b in bodies {
                    let body = b.clone().into_body(None).unwrap();
                    let (lo, hi) = crash_core::mesh::bounds(&body.state.x);
                    let v = body.state.v[0];
                    let m = body.total_mass();
                    self.defs.insert(b.id);
                    self.held.insert(
                        b.id,
                        Held {
                            energy: BodyEnergy {
                                kinetic: 0.5 * m * v.norm_squared(),
                                ..BodyEnergy::default()
                            },
                            load: b,
                            lo,
                            hi,
                            v,
                        },
                    );
                }
                Reply::Ack
            }
            Command::Unload { ids, .. } => Reply::Unloaded(
                ids.iter()
                    .filter_map(|id| self.held.remove(id))
                    .map(|h| h.load)
                    .collect(),
            ),
            Command::Regroup { groups, .. } => {
                self.groups = groups;
                Reply::Ack
            }
            // no kinematic bodies here: copies are held by nobody
            Command::LoadCopies { .. } => Reply::Ack,
            Command::Lend { ids, .. } => Reply::Unloaded(
                ids.iter()
                    .filter_map(|id| self.held.get(id))
                    .map(|h| h.load.clone())
                    .collect(),
            ),
            Command::Reset => {
                self.held.clear();
                Reply::Ack
            }
            Command::Start => Reply::Report(self.report(0.0)),
            Command::Step { dt, .. } => Reply::Report(self.report(dt)),
            Command::Frame(ids) => Reply::Frame(
                ids.iter()
                    .map(|id| {
                        let b = self.held[id].load.clone().into_body(None).unwrap();
                        FrameBody::capture(&b)
                    })
                    .collect(),
            ),
            Command::States(_) => Reply::Error("no states in this bench".into()),
            // the master splits no group here (SplitMode::Off)
            Command::Split(_)
            | Command::Share { .. }
            | Command::Halo(_)
            | Command::Contact(_)
            | Command::Parts
            | Command::Assemble(_)
            | Command::Unsplit
            | Command::PartFrames(_) => Reply::Error("no split groups in this bench".into()),
        }
    }
}

impl WorkerLink for InstantWorker {
    fn send(&mut self, cmd: Command) -> Result<(), LinkError> {
        let r = self.answer(cmd);
        self.queue.push_back(r);
        Ok(())
    }
    fn recv(&mut self) -> Result<Reply, LinkError> {
        self.queue
            .pop_front()
            .ok_or_else(|| LinkError::Protocol("no command pending".into()))
    }
    fn peer(&self) -> String {
        "in-process".into()
    }
    fn has_definition(&self, id: u32) -> bool {
        self.defs.contains(&id)
    }
}

fn bodies(n: usize) -> Vec<Body> {
    let side = (n as f64).sqrt().ceil() as usize;
    let mesh = plate(SIZE, SIZE, 1, 1, ElementKind::Tri);
    (0..n)
        .map(|i| {
            let s = Section::new(Material::steel(), 0.001);
            let mut b = Body::new(
                i as u32,
                &format!("b{i}"),
                &mesh,
                s,
                Stabilization::default(),
            )
            .unwrap();
            let (gx, gy) = ((i % side) as f64, (i / side) as f64);
            // neighbours drift towards each other and apart: a few MEIM changes per step
            let v = Vec3::new(
                0.5 * ((i * 7919) % 13) as f64 - 3.0,
                0.5 * ((i * 104_729) % 11) as f64 - 2.5,
                0.0,
            );
            for (x, vel) in b.state.x.iter_mut().zip(b.state.v.iter_mut()) {
                *x += Vec3::new(gx * SPACING, gy * SPACING, 0.0);
                *vel = v;
            }
            b
        })
        .collect()
}

fn input(n: usize, steps: u64) -> RunInput {
    let b = bodies(n);
    RunInput {
        name: "master-scale".into(),
        briefs: b.iter().map(BodyBrief::of).collect(),
        bodies: BodySource::Built(b.into_iter().map(Some).collect()),
        gravity: Vec3::zeros(),
        contact: ContactConfig::default(),
        config: RunConfig {
            // the instant workers report a stable dt of 1 us: dt = 0.9 us
            end_time: (steps as f64 - 0.5) * 0.9e-6,
            ..RunConfig::default()
        },
        output_interval: 1.0,
        scene_hash: 0,
        results: Default::default(),
    }
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let n: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(10_000);
    let steps: u64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(200);
    println!("master cost per step: {n} bodies, {steps} steps, workers answer at once");
    println!(
        "{:>8} {:>14} {:>14} {:>14} {:>12} {:>10} {:>10}",
        "workers", "step us", "master us", "link us", "migration us", "changes", "migrated"
    );
    for workers in [1usize, 8, 64, 256] {
        let input = input(n, steps);
        let mut links: Vec<InstantWorker> =
            (0..workers).map(|_| InstantWorker::default()).collect();
        let opts = RunOptions::default();
        let t = Instant::now();
        let stats = run_with(input, &mut links, &mut RecordSink::default(), &opts).unwrap();
        let wall = t.elapsed().as_secs_f64();
        let s = stats.steps.max(1) as f64;
        let st = &stats.stages;
        let us = |ns: u64| ns as f64 / s / 1e3;
        println!(
            "{workers:>8} {:>14.1} {:>14.1} {:>14.1} {:>12.1} {:>10} {:>10}",
            wall * 1e6 / s,
            us(st.meim_ns),
            us(st.compute_ns + st.barrier_ns),
            us(st.migration_ns),
            stats.group_changes,
            stats.migrations.len()
        );
    }
}
