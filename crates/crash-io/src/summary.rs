//! summary.json: what a run did, how fast, how trustworthy its result is, and why it
//! stopped if it stopped early. Every field name carries its unit (`_s`, `_j`, `_ns`) or
//! is a count or a ratio (docs/output.md).

use crate::atomic::write_atomic;
use crate::error::{AtPath, IoError};
use crash_core::EnergyTotals;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

pub const SUMMARY_JSON: &str = "summary.json";

/// Hourglass energy over internal energy beyond which a run is doubtful.
pub const HOURGLASS_LIMIT: f64 = 0.10;
/// Energy that contact forces produced (most negative contact energy) over the energy
/// that flowed into contact, beyond which a run is doubtful. A frictionless penalty
/// stores energy while pushing and gives it back; it never makes any.
pub const CONTACT_LIMIT: f64 = 0.10;
/// Largest penetration over the thinner shell's thickness beyond which a run is
/// doubtful.
pub const PENETRATION_LIMIT: f64 = 0.5;
/// Energy-balance limit when a scene gives none (the scene's default `energy_limit`).
pub use crash_core::driver::DEFAULT_ENERGY_LIMIT;

/// serde_json writes non-finite floats as null; read null back as NaN.
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// Run-time error indicators, updated as the run goes (kept in a checkpoint so a
/// restarted run continues its peaks).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Indicators {
    /// The scene's energy-balance limit: the one limit of the warning and the exit code.
    #[serde(deserialize_with = "nan_if_null")]
    pub energy_limit: f64,
    /// The run's energy-balance figure so far: largest |imbalance| over the largest
    /// energy (`crash_core::EnergyLedger::max_error`).
    #[serde(deserialize_with = "nan_if_null")]
    pub energy_balance_error: f64,
    /// Balance error of the last record, relative to the largest energy so far.
    #[serde(deserialize_with = "nan_if_null")]
    pub final_balance_error: f64,
    /// Peak hourglass energy / peak internal energy.
    #[serde(deserialize_with = "nan_if_null")]
    pub hourglass_internal_ratio: f64,
    /// Energy made by contact (−min contact energy, 0 if never negative) over the energy
    /// that flowed into contact.
    #[serde(deserialize_with = "nan_if_null")]
    pub contact_generated_ratio: f64,
    /// Largest penetration / thickness of the thinner body seen in any contact.
    #[serde(deserialize_with = "nan_if_null")]
    pub max_penetration_ratio: f64,
    /// Contact energy of the last record [J] (minus the work of the contact forces).
    #[serde(deserialize_with = "nan_if_null")]
    pub contact_energy_j: f64,
    /// Most negative contact energy seen [J].
    #[serde(deserialize_with = "nan_if_null")]
    pub min_contact_energy_j: f64,
    /// Energy that flowed into contact [J]: the sum of the increases of the contact
    /// energy from record to record.
    #[serde(deserialize_with = "nan_if_null")]
    pub contact_flow_j: f64,
    /// Peak internal and hourglass energies [J] (the hourglass ratio's bases).
    #[serde(deserialize_with = "nan_if_null")]
    pub peak_internal_j: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub peak_hourglass_j: f64,
}

impl Default for Indicators {
    fn default() -> Self {
        Self::new(DEFAULT_ENERGY_LIMIT)
    }
}

/// Which limit a warning is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WarningKind {
    EnergyBalance,
    Hourglass,
    ContactEnergy,
    Penetration,
}

/// One warning, raised once, when its indicator first passed its limit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    pub kind: WarningKind,
    /// The step after which it was raised and its time [s].
    pub step: u64,
    #[serde(deserialize_with = "nan_if_null")]
    pub time_s: f64,
    /// The bodies it concerns, by name (empty: the whole scene).
    pub bodies: Vec<String>,
    /// One sentence: what, how much, the limit.
    pub message: String,
    /// It makes the results doubtful: `crash run` exits with code 4 unless
    /// `--allow-warnings`.
    pub doubtful: bool,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "step {}, t = {:.4e} s", self.step, self.time_s)?;
        if !self.bodies.is_empty() {
            let names: Vec<String> = self.bodies.iter().map(|b| format!("'{b}'")).collect();
            write!(f, ", bodies {}", names.join(" and "))?;
        }
        write!(f, ": {}", self.message)
    }
}

impl Indicators {
    pub fn new(energy_limit: f64) -> Self {
        Self {
            energy_limit,
            energy_balance_error: 0.0,
            final_balance_error: 0.0,
            hourglass_internal_ratio: 0.0,
            contact_generated_ratio: 0.0,
            max_penetration_ratio: 0.0,
            contact_energy_j: 0.0,
            min_contact_energy_j: 0.0,
            contact_flow_j: 0.0,
            peak_internal_j: 0.0,
            peak_hourglass_j: 0.0,
        }
    }

    /// Take one energy record (call every step).
    pub fn observe_energy(&mut self, e: &EnergyTotals) {
        self.final_balance_error = e.balance_error;
        self.energy_balance_error = e.run_error;
        self.peak_internal_j = self.peak_internal_j.max(e.internal);
        self.peak_hourglass_j = self.peak_hourglass_j.max(e.hourglass);
        let rise = e.contact - self.contact_energy_j;
        if rise > 0.0 {
            self.contact_flow_j += rise;
        }
        self.contact_energy_j = e.contact;
        self.min_contact_energy_j = self.min_contact_energy_j.min(e.contact);
        if self.peak_internal_j > 0.0 {
            self.hourglass_internal_ratio = self.peak_hourglass_j / self.peak_internal_j;
        }
        if self.contact_flow_j > 0.0 {
            self.contact_generated_ratio =
                (-self.min_contact_energy_j).max(0.0) / self.contact_flow_j;
        }
    }

    /// Take one penetration, as a fraction of the (thinner) shell thickness.
    pub fn observe_penetration(&mut self, penetration_over_thickness: f64) {
        self.max_penetration_ratio = self.max_penetration_ratio.max(penetration_over_thickness);
    }

    /// The scene-wide indicators past their limits, as (kind, sentence). Penetration is
    /// per body pair: see `penetration_message`.
    pub fn exceeded(&self) -> Vec<(WarningKind, String)> {
        let mut w = Vec::new();
        let e = self.energy_balance_error;
        if e > self.energy_limit || e.is_nan() {
            w.push((
                WarningKind::EnergyBalance,
                format!(
                    "energy-balance error {:.3}% exceeds the scene's limit {:.3}% (energy_limit): the time step or the contact penalty may be too large",
                    100.0 * e,
                    100.0 * self.energy_limit
                ),
            ));
        }
        if self.hourglass_internal_ratio > HOURGLASS_LIMIT {
            w.push((
                WarningKind::Hourglass,
                format!(
                    "hourglass energy is {:.1}% of the peak internal energy (limit {:.0}%): refine the mesh or raise the hourglass stiffness",
                    100.0 * self.hourglass_internal_ratio,
                    100.0 * HOURGLASS_LIMIT
                ),
            ));
        }
        if self.contact_generated_ratio > CONTACT_LIMIT {
            w.push((
                WarningKind::ContactEnergy,
                format!(
                    "contact forces made {:.3e} J of energy, {:.1}% of the {:.3e} J that flowed into contact (limit {:.0}%): a frictionless penalty makes none; lower the time step",
                    -self.min_contact_energy_j,
                    100.0 * self.contact_generated_ratio,
                    self.contact_flow_j,
                    100.0 * CONTACT_LIMIT
                ),
            ));
        }
        w
    }
}

/// The penetration warning's sentence.
pub fn penetration_message(ratio: f64) -> String {
    format!(
        "penetration reached {:.0}% of the thinner shell's thickness (limit {:.0}%)",
        100.0 * ratio,
        100.0 * PENETRATION_LIMIT
    )
}

/// Everything summary.json holds.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub scene: String,
    /// Hash of the scene input (hex).
    pub scene_hash: String,
    pub bodies: usize,
    pub nodes: usize,
    pub elements: usize,
    /// Time steps done (also after a fault).
    pub steps: u64,
    /// Simulated time reached [s] (also after a fault).
    #[serde(deserialize_with = "nan_if_null")]
    pub time_reached_s: f64,
    /// Smallest and largest full step [s]; the last step, shortened to land on the end
    /// time, is `last_dt_s` (0: none) and enters neither.
    #[serde(deserialize_with = "nan_if_null")]
    pub dt_min_s: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub dt_max_s: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub last_dt_s: f64,
    /// Wall-clock time of the run [s].
    #[serde(deserialize_with = "nan_if_null")]
    pub wall_time_s: f64,
    /// Cost per element per step of each pipeline stage (and "total") [ns].
    pub ns_per_element_cycle: BTreeMap<String, f64>,
    /// The barrier per step [us]: "median", and the means of its parts
    /// ("master_codec", "worker_codec", "master_merge": the split groups' shares,
    /// "wire_wake") and of the master's own work
    /// between steps ("master_work").
    #[serde(default)]
    pub barrier_us_per_step: BTreeMap<String, f64>,
    /// The run's energy-balance figure (relative): largest |imbalance| over the largest
    /// energy of the run.
    #[serde(deserialize_with = "nan_if_null")]
    pub energy_balance_error: f64,
    /// The scene's limit for it (relative).
    #[serde(deserialize_with = "nan_if_null")]
    pub energy_limit: f64,
    pub indicators: Indicators,
    /// Every warning raised, in the order raised.
    pub warnings: Vec<Warning>,
    /// `crash_core::hash::state_hash` of the final state, 16 hex digits (empty after a
    /// fault; after an interruption, the state the run stopped at).
    pub final_state_hash: String,
    /// Why the run stopped early, if it did.
    pub fault: Option<String>,
    /// Stopped on request (SIGINT, SIGTERM) after a complete step: `fault` says at
    /// which, the last frame and a restart file (restart.ckp) were written and
    /// `final_state_hash` is the state of that frame. Absent in older files: false.
    #[serde(default)]
    pub interrupted: bool,
    /// The element kernels' instruction-set path ("avx512", "avx2", "baseline") of the
    /// process that computed (empty for crash-master: each worker prints its own).
    #[serde(default)]
    pub simd_path: String,
    /// How the run was spread over its workers.
    #[serde(default)]
    pub cluster: ClusterSummary,
}

/// Workers, groups and migrations of a run (the master's view).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ClusterSummary {
    pub workers: usize,
    /// Bodies moved between workers.
    pub migrations: usize,
    /// MEIM updates that changed the groups, and the most groups at once.
    pub group_changes: u64,
    /// Group changes that kept the split groups as they were (bodies only left them).
    #[serde(default)]
    pub splits_kept: u64,
    /// Groups split over workers, each time a split was made.
    #[serde(default)]
    pub splits: u64,
    /// Steps of split groups whose holders exchanged their part states directly
    /// (protocol v18), and steps whose part states the master relayed.
    #[serde(default)]
    pub halo_direct_steps: u64,
    #[serde(default)]
    pub halo_relayed_steps: u64,
    pub max_groups: usize,
    /// The groups at the end: smallest body id, member ids, worker.
    pub final_groups: Vec<GroupSummary>,
    /// Compute time of each worker summed over the steps [ns] (the balance).
    pub compute_ns_per_worker: Vec<u64>,
}

#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GroupSummary {
    pub group: u32,
    pub bodies: Vec<u32>,
    pub worker: usize,
}

/// Hex form of a state hash as stored in summary.json.
pub fn hash_hex(h: u64) -> String {
    format!("{h:016x}")
}

/// Write summary.json atomically (pretty-printed; non-finite numbers become null).
pub fn write_summary(path: impl AsRef<Path>, s: &Summary) -> Result<(), IoError> {
    let path = path.as_ref();
    let json = serde_json::to_vec_pretty(s).map_err(|e| IoError::Json {
        path: path.to_path_buf(),
        source: e,
    })?;
    write_atomic(path, |w| {
        w.write_all(&json)?;
        w.write_all(b"\n")
    })
}

pub fn read_summary(path: impl AsRef<Path>) -> Result<Summary, IoError> {
    let path = path.as_ref();
    let text = std::fs::read(path).at(path)?;
    serde_json::from_slice(&text).map_err(|e| IoError::Json {
        path: path.to_path_buf(),
        source: e,
    })
}
