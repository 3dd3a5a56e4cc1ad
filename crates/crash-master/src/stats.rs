//! Run statistics: per-stage wall time, MEIM and migration counters (for summary.json).
//! Deserialize: a checkpoint carries them, so a restarted run continues its totals.

use serde::{Deserialize, Serialize};

/// Wall time spent per stage of the master's step [ns], summed over the run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StageTimes {
    /// Slowest worker's compute time per step (what the step cannot go below).
    pub compute_ns: u64,
    /// Rest of the step exchange: messages, serialization, waiting for the slowest
    /// worker (local mode: the other local workers' compute, which runs in turn).
    pub barrier_ns: u64,
    /// dt choice, energy ledger, margin check, MEIM update, grouping, assignment.
    pub meim_ns: u64,
    /// Unloading, moving and loading bodies, regrouping.
    pub migration_ns: u64,
    /// Snapshots and the sink.
    pub output_ns: u64,
}

/// One body moved between workers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Migration {
    /// Moved after this step, before the next.
    pub step: u64,
    pub body: u32,
    pub from: usize,
    pub to: usize,
}

#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RunStats {
    pub workers: usize,
    pub steps: u64,
    pub time: f64,
    /// Smallest and largest full step taken [s] (the last step, shortened to land on
    /// the end time, is `last_dt`).
    pub dt_min: f64,
    pub dt_max: f64,
    /// The shortened last step [s] (0: none).
    #[serde(default)]
    pub last_dt: f64,
    pub wall_s: f64,
    pub stages: StageTimes,
    /// Largest relative energy-balance error of the run.
    pub max_energy_error: f64,
    pub migrations: Vec<Migration>,
    /// MEIM updates that changed the groups.
    pub group_changes: u64,
    pub max_groups: usize,
    /// Groups (body ids) and their worker at the end.
    pub final_groups: Vec<(Vec<u32>, usize)>,
    /// `crash_core::hash::state_hash` of the final state (0 if the run failed).
    pub final_hash: u64,
    pub frames: u64,
    /// Compute time of each worker summed over the steps [ns].
    #[serde(default)]
    pub worker_compute_ns: Vec<u64>,
}
