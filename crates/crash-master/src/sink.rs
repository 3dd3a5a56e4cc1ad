//! Where results go: the master hands every energy row, MEIM change and frame to a
//! `Sink` (crash-io writers in the binaries, memory in tests).

use crate::checkpoint::MasterCheckpoint;
use crate::error::MasterError;
use crate::stats::RunStats;
use crash_core::contact::PairStats;
use crash_core::hash::StateHasher;
use crash_core::{BodyReport, EnergyTotals, NodeProbe};
use crash_io::FrameBody;

pub use crate::error::SinkError;

/// Receives the results of a run, in time order.
pub trait Sink {
    /// Scene energy totals after the start (step 0) and after every step.
    fn energy(&mut self, step: u64, time: f64, totals: &EnergyTotals) -> Result<(), SinkError>;
    /// The MEIM edges (possible contacts, body id pairs a < b) whenever they change.
    fn contacts(&mut self, _step: u64, _time: f64, _pairs: &[(u32, u32)]) -> Result<(), SinkError> {
        Ok(())
    }
    /// Contact statistics of the candidate pairs (sorted by pair) after the start and
    /// after every step.
    fn contact_stats(
        &mut self,
        _step: u64,
        _time: f64,
        _stats: &[PairStats],
    ) -> Result<(), SinkError> {
        Ok(())
    }
    /// The groups (who computes what) at a time they changed, and at every output time.
    fn groups(&mut self, _step: u64, _time: f64, _rows: &[GroupRow]) -> Result<(), SinkError> {
        Ok(())
    }

    /// The result rows due at this step (matsum.csv, rcforc.csv, nodout.csv,
    /// spcforc.csv), after its energy row.
    fn results(&mut self, _step: u64, _time: f64, _rows: &ResultRows<'_>) -> Result<(), SinkError> {
        Ok(())
    }
    /// The loop's state after a step, every `RunOptions::checkpoint_every` steps
    /// (after that step's rows and frame). Keep it to continue the run later.
    fn checkpoint(&mut self, _state: &MasterCheckpoint) -> Result<(), SinkError> {
        Ok(())
    }
    /// A checkpoint the run may roll back to (after a worker was lost), in memory:
    /// remember what `rollback` needs to return to it. Called after `checkpoint`.
    fn remember(&mut self, _state: &MasterCheckpoint) -> Result<(), SinkError> {
        Ok(())
    }
    /// The run went back to `state` (the last checkpoint handed to `remember`): forget
    /// every row and frame after its step (a torn last row included), so the steps
    /// that follow again are written once.
    fn rollback(&mut self, state: &MasterCheckpoint) -> Result<(), SinkError> {
        Err(format!(
            "this output cannot go back to step {} to continue without a lost worker",
            state.clock.step
        )
        .into())
    }
    /// A frame at an output time begins; its bodies follow in id order (`frame_body`),
    /// then `frame_end`.
    fn frame_begin(&mut self, step: u64, time: f64) -> Result<(), SinkError>;
    fn frame_body(&mut self, body: FrameBody) -> Result<(), SinkError>;
    fn frame_end(&mut self) -> Result<(), SinkError>;
    /// The run ended: normally (`error` None, the final frame was written) or not (the
    /// frames written so far are the last complete ones).
    fn finish(&mut self, stats: &RunStats, error: Option<&MasterError>) -> Result<(), SinkError>;
}

/// One group at one time (a row of groups.csv).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GroupRow {
    /// The group's name: its smallest body id.
    pub group: u32,
    /// Its bodies' names, in id order (read-only copies of kinematic bodies not listed).
    pub bodies: Vec<String>,
    pub worker: usize,
    pub elements: usize,
    /// The group's compute time in the last step [ns] (0 before the first step).
    pub step_ns: u64,
}

/// What each result file gets at one step (None: that file is not due).
#[derive(Debug, Clone, Copy, Default)]
pub struct ResultRows<'a> {
    /// Per-body energies (matsum.csv), in body-id order.
    pub matsum: Option<&'a [BodyReport]>,
    /// Contact pairs, sorted (rcforc.csv: those with pushed nodes).
    pub rcforc: Option<&'a [PairStats]>,
    /// History nodes with their mesh-file node ids, sorted by body and node.
    pub nodout: Option<&'a [(u64, NodeProbe)]>,
    /// Per-body reports (spcforc.csv: those with a reaction).
    pub spcforc: Option<&'a [BodyReport]>,
}

/// One energy row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnergyRecord {
    pub step: u64,
    pub time: f64,
    pub totals: EnergyTotals,
}

/// Keeps energy rows, frame times, MEIM changes and the final state hash in memory.
#[derive(Debug, Default)]
pub struct RecordSink {
    pub energy: Vec<EnergyRecord>,
    pub frames: Vec<(u64, f64, u64)>,
    pub contacts: Vec<(u64, Vec<(u32, u32)>)>,
    /// Steps (and times) with at least one pushed node, and the pairs' statistics.
    pub contact_stats: Vec<(u64, f64, Vec<PairStats>)>,
    /// Group rows handed over: (step, time, rows).
    pub groups: Vec<(u64, f64, Vec<GroupRow>)>,
    /// Hash of the last frame (the final state after a normal end).
    pub last_hash: Option<u64>,
    /// Every checkpoint handed over.
    pub checkpoints: Vec<MasterCheckpoint>,
    /// The frame being received (step, time, hash so far).
    open: Option<(u64, f64, StateHasher)>,
    pub finished: Option<Result<RunStats, String>>,
}

impl Sink for RecordSink {
    fn groups(&mut self, step: u64, time: f64, rows: &[GroupRow]) -> Result<(), SinkError> {
        self.groups.push((step, time, rows.to_vec()));
        Ok(())
    }

    fn energy(&mut self, step: u64, time: f64, totals: &EnergyTotals) -> Result<(), SinkError> {
        self.energy.push(EnergyRecord {
            step,
            time,
            totals: *totals,
        });
        Ok(())
    }

    fn contacts(&mut self, step: u64, _time: f64, pairs: &[(u32, u32)]) -> Result<(), SinkError> {
        self.contacts.push((step, pairs.to_vec()));
        Ok(())
    }

    fn contact_stats(
        &mut self,
        step: u64,
        time: f64,
        stats: &[PairStats],
    ) -> Result<(), SinkError> {
        if stats.iter().any(|s| s.active_nodes > 0) {
            self.contact_stats.push((step, time, stats.to_vec()));
        }
        Ok(())
    }

    fn checkpoint(&mut self, state: &MasterCheckpoint) -> Result<(), SinkError> {
        self.checkpoints.push(state.clone());
        Ok(())
    }

    fn rollback(&mut self, state: &MasterCheckpoint) -> Result<(), SinkError> {
        let step = state.clock.step;
        self.energy.retain(|r| r.step <= step);
        self.frames.retain(|f| f.0 <= step);
        self.contacts.retain(|c| c.0 <= step);
        self.contact_stats.retain(|c| c.0 <= step);
        self.open = None;
        self.last_hash = self.frames.last().map(|f| f.2);
        Ok(())
    }

    fn frame_begin(&mut self, step: u64, time: f64) -> Result<(), SinkError> {
        self.open = Some((step, time, StateHasher::default()));
        Ok(())
    }

    fn frame_body(&mut self, b: FrameBody) -> Result<(), SinkError> {
        let (_, _, h) = self.open.as_mut().ok_or("a frame body outside a frame")?;
        h.add(b.id, &b.x, &b.v, &b.w);
        Ok(())
    }

    fn frame_end(&mut self) -> Result<(), SinkError> {
        let (step, time, h) = self.open.take().ok_or("the end of a frame never begun")?;
        self.frames.push((step, time, h.finish()));
        self.last_hash = Some(h.finish());
        Ok(())
    }

    fn finish(&mut self, stats: &RunStats, error: Option<&MasterError>) -> Result<(), SinkError> {
        self.finished = Some(match error {
            None => Ok(stats.clone()),
            Some(e) => Err(e.to_string()),
        });
        Ok(())
    }
}
