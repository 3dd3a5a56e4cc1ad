//! Energy balance: E_kin + E_int + E_hg + E_contact + E_damping - W_ext = E_0.

use crate::body::{BodyEnergy, VelocityProgram};
use crate::clock::Clock;
use crate::contact::{KinLoad, PairStats};
use crate::curve::TimeCurve;
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
    /// The run's energy-balance figure so far (`EnergyLedger::max_error` after this
    /// record): largest |imbalance| over the largest energy. The one figure the
    /// indicators, the warning and the exit code judge against the scene's limit.
    #[serde(default)]
    pub run_error: f64,
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
    /// Take the record of a full step (or the start).
    pub fn update(&mut self, t: EnergyTotals) -> EnergyTotals {
        self.record(t, true)
    }

    /// Take a record; `counts` false for the record after the last step when it was
    /// shortened to land on the end time: its row is still computed (balance error
    /// against the figures so far) but it enters neither the largest energy nor the
    /// largest imbalance. With h_last << h the shadow internal energy (docs/theory.md
    /// section 6) and the half-step kinetic energy are taken at a time level the scheme
    /// does not conserve, which shows as a jump of the order of the high-frequency
    /// content (the `last_shortened_step_does_not_distort_the_energy_figure` test).
    pub fn record(&mut self, mut t: EnergyTotals, counts: bool) -> EnergyTotals {
        let total = t.total();
        let e0 = *self.e0.get_or_insert(total);
        let size = (t.kinetic + t.internal + t.hourglass + t.damping + t.contact.abs())
            .max(t.external.abs())
            .max(e0.abs());
        if counts && size > self.scale {
            self.scale = size;
        }
        t.balance_error = if self.scale > 0.0 {
            (total - e0) / self.scale
        } else {
            0.0
        };
        let abs = (total - e0).abs();
        if counts && (abs > self.max_abs_error || abs.is_nan()) {
            self.max_abs_error = abs;
        }
        t.run_error = self.max_error();
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

/// Work contact has done on each kinematic body so far (a prescribed body's motion never
/// feels contact; the work is the same figure the body's reaction pays, so it enters
/// both the contact and the external column). Counted by the integration's rule for
/// every other body, W += hbar f_n . (v_{n-1/2} + v_{n+1/2}) / 2, from the per-pair loads
/// of the pass at x_n (`PairStats::kin_a` / `kin_b`), in pair order: every loop (the
/// single-group driver, the master over any number of workers) performs the same
/// additions in the same order, whichever groups hold read-only copies of the body.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct KinematicWork {
    /// (kinematic body id, work so far [J]), sorted by id.
    work: Vec<(u32, f64)>,
    /// The velocity programs and load curves of each body in `work` (same order).
    programs: Vec<Vec<VelocityProgram>>,
    #[serde(default)]
    curves: Vec<Vec<TimeCurve>>,
    /// The last pass's loads, in pair order: (body id, load).
    pending: Vec<(u32, KinLoad)>,
}

impl KinematicWork {
    /// Tracks the kinematic bodies given with their velocity programs and load curves
    /// (any order).
    pub fn new(
        bodies: impl IntoIterator<Item = (u32, Vec<VelocityProgram>, Vec<TimeCurve>)>,
    ) -> Self {
        let mut b: Vec<_> = bodies.into_iter().collect();
        b.sort_by_key(|w| w.0);
        b.dedup_by_key(|w| w.0);
        let work = b.iter().map(|(id, _, _)| (*id, 0.0)).collect();
        let (programs, curves) = b.into_iter().map(|(_, p, c)| (p, c)).unzip();
        Self {
            work,
            programs,
            curves,
            pending: Vec::new(),
        }
    }

    /// The work of the last pass's loads over the step of length `h` from `clock`: the
    /// velocity after it is the prescribed one of that step (`VelocityProgram::over_step`).
    pub fn settle(&mut self, clock: &Clock, h: f64) {
        let hbar = 0.5 * (clock.last_dt + h);
        for (id, load) in &self.pending {
            let Ok(k) = self.work.binary_search_by_key(id, |w| w.0) else {
                continue;
            };
            let mut p_new = 0.0;
            for (prog, f) in &load.by_program {
                if let Some(vp) = self.programs[k].get(*prog as usize) {
                    let curves = self.curves.get(k).map_or(&[][..], |c| &c[..]);
                    p_new += f.dot(&vp.over_step(clock.time, h, curves).0);
                }
            }
            self.work[k].1 += hbar * (0.5 * (load.power + p_new));
        }
    }

    /// Keep one force pass's loads on kinematic bodies (`stats` sorted by pair, as
    /// every loop has them) for the next `settle`.
    pub fn add(&mut self, stats: &[PairStats]) {
        self.pending.clear();
        for s in stats {
            if !s.kin_a.is_empty() {
                self.pending.push((s.a, s.kin_a.clone()));
            }
            if s.a != s.b && !s.kin_b.is_empty() {
                self.pending.push((s.b, s.kin_b.clone()));
            }
        }
    }

    /// The work so far on body `id` (0 for a body not tracked).
    pub fn of(&self, id: u32) -> f64 {
        self.work
            .binary_search_by_key(&id, |w| w.0)
            .map_or(0.0, |k| self.work[k].1)
    }

    /// Into the reports' energy records: work W done by contact on a kinematic body
    /// is absorbed by contact (-W) and paid by its prescribed motion (-W external).
    pub fn apply(&self, reports: &mut [crate::group::BodyReport]) {
        for r in reports {
            if let Ok(k) = self.work.binary_search_by_key(&r.id, |w| w.0) {
                let w = self.work[k].1;
                r.energy.contact -= w;
                r.energy.external -= w;
            }
        }
    }
}
