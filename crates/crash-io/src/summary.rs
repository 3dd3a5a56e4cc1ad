//! summary.json: what a run did, how fast, and how trustworthy its result is.

use crate::atomic::write_atomic;
use crate::error::{AtPath, IoError};
use crash_core::EnergyTotals;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

pub const SUMMARY_JSON: &str = "summary.json";

/// Thresholds of the warnings (industry practice, see docs/output.md).
pub const HOURGLASS_LIMIT: f64 = 0.10;
pub const CONTACT_LIMIT: f64 = 0.10;
pub const BALANCE_LIMIT: f64 = 0.01;
pub const PENETRATION_LIMIT: f64 = 0.5;

/// serde_json writes non-finite floats as null; read null back as NaN.
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// Run-time error indicators, updated as the run goes (serde: keep it in a checkpoint
/// so a restarted run continues its peaks).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Indicators {
    /// Energy-balance error (relative to the largest energy) at the end.
    #[serde(deserialize_with = "nan_if_null")]
    pub final_balance_error: f64,
    /// Largest |energy-balance error| seen.
    #[serde(deserialize_with = "nan_if_null")]
    pub peak_balance_error: f64,
    /// Peak hourglass energy / peak internal energy.
    #[serde(deserialize_with = "nan_if_null")]
    pub hourglass_internal_ratio: f64,
    /// Largest |contact energy| / peak internal energy.
    #[serde(deserialize_with = "nan_if_null")]
    pub contact_internal_ratio: f64,
    /// Largest penetration / thickness of the thinner body seen in any contact.
    #[serde(deserialize_with = "nan_if_null")]
    pub max_penetration_ratio: f64,
    /// Most negative contact energy seen [J] (clearly negative means contact did work).
    #[serde(deserialize_with = "nan_if_null")]
    pub min_contact_energy: f64,
    /// Peak internal, hourglass and |contact| energies [J] (the ratios' bases).
    #[serde(deserialize_with = "nan_if_null")]
    pub peak_internal: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub peak_hourglass: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub peak_contact: f64,
}

impl Indicators {
    /// Take one energy record (call every step or every history row).
    pub fn observe_energy(&mut self, e: &EnergyTotals) {
        self.final_balance_error = e.balance_error;
        if e.balance_error.abs() > self.peak_balance_error || e.balance_error.is_nan() {
            self.peak_balance_error = e.balance_error.abs();
        }
        self.peak_internal = self.peak_internal.max(e.internal);
        self.peak_hourglass = self.peak_hourglass.max(e.hourglass);
        self.peak_contact = self.peak_contact.max(e.contact.abs());
        self.min_contact_energy = self.min_contact_energy.min(e.contact);
        if self.peak_internal > 0.0 {
            self.hourglass_internal_ratio = self.peak_hourglass / self.peak_internal;
            self.contact_internal_ratio = self.peak_contact / self.peak_internal;
        }
    }

    /// Take one penetration, as a fraction of the (thinner) shell thickness.
    pub fn observe_penetration(&mut self, penetration_over_thickness: f64) {
        self.max_penetration_ratio = self.max_penetration_ratio.max(penetration_over_thickness);
    }

    /// Human-readable warnings for every indicator beyond its limit.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.peak_balance_error > BALANCE_LIMIT || self.peak_balance_error.is_nan() {
            w.push(format!(
                "energy balance error reached {:.2}% (limit {:.0}%): the time step or the contact penalty may be too large",
                100.0 * self.peak_balance_error,
                100.0 * BALANCE_LIMIT
            ));
        }
        if self.hourglass_internal_ratio > HOURGLASS_LIMIT {
            w.push(format!(
                "hourglass energy is {:.1}% of the internal energy (limit {:.0}%): refine the mesh or raise hourglass stiffness",
                100.0 * self.hourglass_internal_ratio,
                100.0 * HOURGLASS_LIMIT
            ));
        }
        if self.contact_internal_ratio > CONTACT_LIMIT {
            w.push(format!(
                "contact energy is {:.1}% of the peak internal energy (limit {:.0}%)",
                100.0 * self.contact_internal_ratio,
                100.0 * CONTACT_LIMIT
            ));
        }
        if self.min_contact_energy < -0.01 * self.peak_internal && self.peak_internal > 0.0 {
            w.push(format!(
                "contact energy went negative ({:.3e} J): contact forces did net work",
                self.min_contact_energy
            ));
        }
        if self.max_penetration_ratio > PENETRATION_LIMIT {
            w.push(format!(
                "penetration reached {:.0}% of the shell thickness (limit {:.0}%)",
                100.0 * self.max_penetration_ratio,
                100.0 * PENETRATION_LIMIT
            ));
        }
        w
    }
}

/// Everything summary.json holds. Units: seconds, joules, nanoseconds.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub scene: String,
    /// Hash of the scene input (hex).
    pub scene_hash: String,
    pub bodies: usize,
    pub nodes: usize,
    pub elements: usize,
    pub steps: u64,
    /// Simulated time reached [s].
    #[serde(deserialize_with = "nan_if_null")]
    pub end_time: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub dt_min: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub dt_max: f64,
    /// Wall-clock time of the run [s].
    #[serde(deserialize_with = "nan_if_null")]
    pub wall_time_s: f64,
    /// Cost per element per step of each pipeline stage (and "total") [ns].
    pub ns_per_element_cycle: BTreeMap<String, f64>,
    /// Largest |energy-balance error| (relative).
    #[serde(deserialize_with = "nan_if_null")]
    pub max_energy_balance_error: f64,
    pub indicators: Indicators,
    pub warnings: Vec<String>,
    /// `crash_core::hash::state_hash` of the final state, 16 hex digits.
    pub final_state_hash: String,
    /// Why the run stopped early, if it did.
    pub fault: Option<String>,
    /// The element kernels' instruction-set path ("avx512", "avx2", "baseline") of the
    /// process that computed (empty for crash-master: each worker prints its own).
    #[serde(default)]
    pub simd_path: String,
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
