//! crash-master: the global time loop of a run.
//!
//! The master holds the MEIM (bodies and their possible contacts, a petgraph
//! StableGraph), groups bodies into its connected components, places groups on workers
//! (balanced, sticky), drives the step barrier, chooses the global time step exactly as
//! the single-process driver does, migrates bodies between workers and writes what the
//! workers send at output times.
//!
//! The same loop drives any `crash_link::WorkerLink`: in-process workers
//! (`crash_worker::LocalWorker`, used by `crash run`) or worker processes over gRPC
//! ([`server::Cluster`], used by the `crash-master` binary). This crate depends on
//! crash-link, never on crash-worker. Architecture: docs/architecture.md.

pub mod assign;
pub mod cert;
pub mod checkpoint;
pub mod error;
pub mod file_sink;
pub mod groups_csv;
pub mod guard;
pub mod heartbeat;
pub mod input;
pub mod join;
pub mod joiner;
mod lane;
mod master;
pub mod meim;
pub mod pairs;
pub mod remote_link;
pub mod result_files;
pub mod server;
pub mod session;
pub mod sink;
pub mod stats;
pub mod stop;

pub use checkpoint::MasterCheckpoint;
pub use error::MasterError;
pub use file_sink::FileSink;
pub use file_sink::{frame_format, read_restart, read_restart_keyed, RestartFile, RESTART_FILE};
pub use input::{BodySource, CostModel, ResultRequest, RunInput, RunOptions, RunSize, SplitMode};
pub use join::{Newcomers, NoNewcomers};
pub use remote_link::RemoteWorker;
pub use server::{Cluster, RemoteOptions, TlsIdentity};
pub use session::Session;
pub use sink::{EnergyRecord, GroupRow, RecordSink, ResultRows, Sink, SinkError};
pub use stats::{BarrierStats, Migration, RunStats, StageTimes};

use crash_link::WorkerLink;
use std::time::Instant;

/// Run a scene on the given workers (any `WorkerLink`): start, step to the end time,
/// final frame. On any error the workers are told to stop, the sink is told why (the
/// frames already written are the last complete ones), and the error is returned.
pub fn run_with<L: WorkerLink>(
    input: RunInput,
    links: &mut [L],
    sink: &mut dyn Sink,
    opts: &RunOptions,
) -> Result<RunStats, MasterError> {
    drive(input, None, links, None, sink, opts)
}

/// Continue a run from a checkpoint (`Sink::checkpoint`) of the same scene to the
/// input's end time, as `run_with` would have, on any number of workers. The sink
/// receives only what follows the checkpoint.
pub fn resume_with<L: WorkerLink>(
    input: RunInput,
    state: MasterCheckpoint,
    links: &mut [L],
    sink: &mut dyn Sink,
    opts: &RunOptions,
) -> Result<RunStats, MasterError> {
    drive(input, Some(state), links, None, sink, opts)
}

fn drive<'a, L: WorkerLink>(
    input: RunInput,
    resume: Option<MasterCheckpoint>,
    links: &'a mut [L],
    joiner: Option<&'a mut (dyn Newcomers<L> + 'a)>,
    sink: &mut dyn Sink,
    opts: &RunOptions,
) -> Result<RunStats, MasterError> {
    let wall = Instant::now();
    // wall time before the checkpoint (the time lost after it is not counted)
    let wall_before = resume.as_ref().map_or(0.0, |c| c.stats.wall_s);
    let fresh = resume.is_none();
    let mut s = match Session::start_with(input, resume, links, joiner, sink, opts) {
        Ok(s) => s,
        Err(e) => {
            let stats = RunStats {
                wall_s: wall_before + wall.elapsed().as_secs_f64(),
                ..RunStats::default()
            };
            let _ = sink.finish(&stats, Some(&e));
            return Err(e);
        }
    };
    let mut ck = Checkpoints {
        every: opts.checkpoint_every,
        seconds: opts.checkpoint_seconds,
        last: Instant::now(),
        saved: None,
        wall,
        wall_before,
    };
    // the first rollback point: the start (or the resumed checkpoint)
    let mut result = if ck.keep() {
        ck.take(&mut s, sink, false)
    } else {
        Ok(())
    };
    if result.is_ok() && fresh {
        result = s.split();
    }
    if result.is_ok() {
        result = loop {
            let r = to_the_end(&mut s, sink, &mut ck);
            let (state, replay) = match (&r, &ck.saved) {
                // a worker gone or frozen: drop it, go back to the last checkpoint on
                // the others, replay
                (Err(_), Some(state)) if s.has_lost() => (state, false),
                // the workers could not exchange halos directly: go back and relay
                (Err(MasterError::DirectHalo { .. }), Some(state)) => (state, false),
                // a fault: replayed on the other workers before it is believed
                (Err(MasterError::Fault(_)), Some(state)) if s.can_replay_fault() => (state, true),
                _ => break r,
            };
            if let Err(e) = &r {
                if !replay {
                    tracing::warn!("{e}");
                }
            }
            let back = if replay {
                s.replay_fault(state)
            } else {
                s.recover(state)
            }
            .and_then(|()| sink.rollback(state).map_err(MasterError::sink));
            if let Err(e) = back {
                // keep the checkpoint on disk to continue with --resume
                if sink.rollback(state).is_ok() {
                    let _ = sink.checkpoint(state);
                }
                break Err(e);
            }
            tracing::info!(
                "continuing from step {} ({} workers dropped so far)",
                state.clock.step,
                s.recoveries()
            );
        };
    }
    s.stats_mut().wall_s = wall_before + wall.elapsed().as_secs_f64();
    if let Err(MasterError::Fault(_)) = &result {
        // the last complete step's rows, if a split group's pass held them
        if let Err(e) = s.rows_after_fault(sink) {
            tracing::warn!("the contact rows of the step before the fault: {e}");
        }
    }
    s.end(result.as_ref().err());
    match result {
        Ok(_) => {
            let stats = s.stats().clone();
            sink.finish(&stats, None).map_err(MasterError::sink)?;
            Ok(stats)
        }
        Err(e @ MasterError::Interrupted { .. }) => {
            let stats = s.stats().clone();
            let _ = sink.finish(&stats, Some(&e));
            Err(e)
        }
        Err(e) => {
            s.record_progress();
            let mut stats = s.stats().clone();
            stats.final_hash = 0;
            let _ = sink.finish(&stats, Some(&e));
            Err(e)
        }
    }
}

/// When checkpoints are taken, and the last one (the rollback point).
struct Checkpoints {
    /// Every this many steps, on disk too (0: never).
    every: u64,
    /// After this much wall time since the last one [s] (0: never).
    seconds: f64,
    last: Instant,
    saved: Option<MasterCheckpoint>,
    wall: Instant,
    wall_before: f64,
}

impl Checkpoints {
    /// Whether checkpoints are kept at all (without, a lost worker ends the run).
    fn keep(&self) -> bool {
        self.every > 0 || self.seconds > 0.0
    }

    /// Whether one is due after step `step`.
    fn due(&self, step: u64) -> bool {
        (self.every > 0 && step.is_multiple_of(self.every))
            || (self.seconds > 0.0 && self.last.elapsed().as_secs_f64() >= self.seconds)
    }

    /// Take one: in memory (the rollback point) and, when asked, on disk.
    fn take<L: WorkerLink>(
        &mut self,
        s: &mut Session<'_, L>,
        sink: &mut dyn Sink,
        disk: bool,
    ) -> Result<(), MasterError> {
        let t = Instant::now();
        s.stats_mut().wall_s = self.wall_before + self.wall.elapsed().as_secs_f64();
        let state = s.checkpoint()?;
        s.settle_rows(sink)?;
        if disk {
            sink.checkpoint(&state).map_err(MasterError::sink)?;
        }
        sink.remember(&state).map_err(MasterError::sink)?;
        s.stats_mut().stages.output_ns += t.elapsed().as_nanos() as u64;
        self.saved = Some(state);
        self.last = Instant::now();
        Ok(())
    }
}

/// Step to the end time (checkpoints as due), then the final frame. A stop request
/// (SIGTERM) ends it after a complete step with a checkpoint on disk and the final frame.
fn to_the_end<L: WorkerLink>(
    s: &mut Session<'_, L>,
    sink: &mut dyn Sink,
    ck: &mut Checkpoints,
) -> Result<(), MasterError> {
    while !s.finished() {
        s.step(sink)?;
        if stop::requested() {
            // the step is complete: checkpoint, then the final frame and summary
            ck.take(s, sink, true)?;
            s.finish(sink)?;
            let c = s.clock();
            return Err(MasterError::Interrupted {
                step: c.step,
                time: c.time,
            });
        }
        if ck.keep() && ck.due(s.clock().step) && !s.finished() {
            ck.take(s, sink, ck.every > 0)?;
        }
    }
    s.finish(sink).map(|_| ())
}

/// Remote mode: the master loop over the worker processes attached to `cluster`, and
/// those that attach during the run.
pub fn run_remote(
    input: RunInput,
    cluster: &mut Cluster,
    sink: &mut dyn Sink,
    opts: &RunOptions,
) -> Result<RunStats, MasterError> {
    let (links, joiner) = cluster.parts();
    drive(input, None, links, Some(joiner), sink, opts)
}

/// Remote mode from a checkpoint: any number of workers.
pub fn resume_remote(
    input: RunInput,
    state: MasterCheckpoint,
    cluster: &mut Cluster,
    sink: &mut dyn Sink,
    opts: &RunOptions,
) -> Result<RunStats, MasterError> {
    let (links, joiner) = cluster.parts();
    drive(input, Some(state), links, Some(joiner), sink, opts)
}
