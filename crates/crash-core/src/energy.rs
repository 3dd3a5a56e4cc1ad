//! Energy balance: E_kin + E_int + E_hg + E_contact + E_damping - W_ext = E_0.

use crate::body::BodyEnergy;
use serde::{Deserialize, Serialize};

/// Energy totals of a whole scene at one time, with the balance error relative to the
/// largest energy seen so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyTotals {
    pub kinetic: f64,
    pub internal: f64,
    pub hourglass: f64,
    pub contact: f64,
    pub damping: f64,
    pub external: f64,
    /// (E_kin + E_int + E_hg + E_c + E_d - W - E_0) / max energy seen.
    pub balance_error: f64,
}

impl EnergyTotals {
    /// Sum body records in the given (body id) order: the order is part of determinism.
    pub fn sum<'a>(bodies: impl IntoIterator<Item = &'a BodyEnergy>) -> Self {
        let mut t = Self::default();
        for e in bodies {
            t.kinetic += e.kinetic;
            t.internal += e.internal;
            t.hourglass += e.hourglass;
            t.contact += e.contact;
            t.damping += e.damping;
            t.external += e.external;
        }
        t
    }

    /// E_kin + E_int + E_hg + E_c + E_d - W.
    pub fn total(&self) -> f64 {
        self.kinetic + self.internal + self.hourglass + self.contact + self.damping - self.external
    }
}

/// Tracks E_0, the largest energy seen and the largest balance error.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct EnergyLedger {
    pub e0: Option<f64>,
    /// Largest energy seen so far.
    pub scale: f64,
    /// Largest absolute imbalance |E - E_0| seen so far [J].
    pub max_abs_error: f64,
    pub last: EnergyTotals,
    /// Consecutive steps whose relative error exceeded the runaway limit.
    pub over_limit: u32,
}

impl EnergyLedger {
    pub fn update(&mut self, mut t: EnergyTotals) -> EnergyTotals {
        let total = t.total();
        let e0 = *self.e0.get_or_insert(total);
        let size = (t.kinetic + t.internal + t.hourglass + t.damping + t.contact.abs())
            .max(t.external.abs())
            .max(e0.abs());
        if size > self.scale {
            self.scale = size;
        }
        t.balance_error = if self.scale > 0.0 {
            (total - e0) / self.scale
        } else {
            0.0
        };
        let abs = (total - e0).abs();
        if abs > self.max_abs_error || abs.is_nan() {
            self.max_abs_error = abs;
        }
        self.last = t;
        t
    }

    /// Largest imbalance of the run relative to the largest energy of the run. (The
    /// running relative error is noisy in the first steps of a run that starts from
    /// rest, when all energies are near zero; this measure is not.)
    pub fn max_error(&self) -> f64 {
        if self.scale > 0.0 {
            self.max_abs_error / self.scale
        } else {
            0.0
        }
    }
}
