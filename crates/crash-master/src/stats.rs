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

/// The barrier of every step, in parts (issue 16: measured, then cut). Per step, the
/// barrier is the step exchange's wall time less the slowest worker's compute; it splits
/// into the master's encoding and decoding, the slowest worker's decoding and encoding
/// (`StepReport::codec_ns`), the master's merge of the split groups' shares (their
/// contact statistics, reports and closing-speed figures), and the rest: the wire, the
/// system calls and waking the processes.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct BarrierStats {
    pub steps: u64,
    pub master_codec_ns: u64,
    pub worker_codec_ns: u64,
    #[serde(default)]
    pub master_merge_ns: u64,
    pub wire_wake_ns: u64,
    /// Steps per barrier length in whole microseconds (the last bin: this many or more).
    pub histogram_us: Vec<u64>,
}

/// Bins of the barrier histogram: 1 us each up to 5 ms.
const BARRIER_BINS: usize = 5001;

impl BarrierStats {
    /// One step's barrier (`total` = exchange wall time - slowest compute).
    pub fn record(&mut self, total: u64, master_codec: u64, worker_codec: u64, merge: u64) {
        self.steps += 1;
        self.master_codec_ns += master_codec;
        self.worker_codec_ns += worker_codec;
        self.master_merge_ns += merge;
        self.wire_wake_ns += total.saturating_sub(master_codec + worker_codec + merge);
        if self.histogram_us.len() != BARRIER_BINS {
            self.histogram_us.resize(BARRIER_BINS, 0);
        }
        let bin = ((total / 1000) as usize).min(BARRIER_BINS - 1);
        self.histogram_us[bin] += 1;
    }

    /// Median barrier per step [us] (to the microsecond; NaN without steps).
    pub fn median_us(&self) -> f64 {
        let half = self.steps.div_ceil(2);
        let mut seen = 0;
        for (us, &n) in self.histogram_us.iter().enumerate() {
            seen += n;
            if seen >= half && n > 0 {
                return us as f64 + 0.5;
            }
        }
        f64::NAN
    }

    /// Mean of each part per step [us]: master codec, worker codec, master merge, wire
    /// and wake-up.
    pub fn parts_us(&self) -> [f64; 4] {
        let s = self.steps.max(1) as f64 * 1e3;
        [
            self.master_codec_ns as f64 / s,
            self.worker_codec_ns as f64 / s,
            self.master_merge_ns as f64 / s,
            self.wire_wake_ns as f64 / s,
        ]
    }
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
    /// Group changes that kept the split groups (`time_loop`).
    pub splits_kept: u64,
    /// Groups split over workers (each time a split is made).
    #[serde(default)]
    pub splits: u64,
    /// Steps of split groups whose holders exchanged their part states directly, and
    /// those the master relayed.
    #[serde(default)]
    pub halo_direct_steps: u64,
    #[serde(default)]
    pub halo_relayed_steps: u64,
    pub max_groups: usize,
    /// Groups (body ids) and their worker at the end.
    pub final_groups: Vec<(Vec<u32>, usize)>,
    /// `crash_core::hash::state_hash` of the final state (0 if the run failed).
    pub final_hash: u64,
    pub frames: u64,
    /// Compute time of each worker summed over the steps [ns].
    #[serde(default)]
    pub worker_compute_ns: Vec<u64>,
    #[serde(default)]
    pub barrier: BarrierStats,
}

#[cfg(test)]
mod tests {
    use super::BarrierStats;

    #[test]
    fn barrier_median_is_the_middle_step_and_parts_add_up_to_the_total() {
        let mut b = BarrierStats::default();
        // 5 steps: 10, 20, 30, 40 us and one of 9 ms (beyond the last bin)
        for (total, m, w, g) in [
            (10_000, 1_000, 2_000, 500),
            (20_000, 1_000, 2_000, 500),
            (30_500, 1_000, 2_000, 500),
            (40_000, 1_000, 2_000, 500),
            (9_000_000, 1_000, 2_000, 500),
        ] {
            b.record(total, m, w, g);
        }
        assert_eq!(b.median_us(), 30.5);
        let [mc, wc, mg, ww] = b.parts_us();
        assert_eq!(mg, 0.5);
        let mean = (10_000 + 20_000 + 30_500 + 40_000 + 9_000_000) as f64 / 5.0 / 1e3;
        assert!(
            (mc + wc + mg + ww - mean).abs() < 1e-9,
            "{mc} + {wc} + {mg} + {ww} vs {mean}"
        );
        assert!(BarrierStats::default().median_us().is_nan());
    }
}
