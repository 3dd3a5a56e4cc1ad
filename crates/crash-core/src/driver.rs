//! The in-process time loop over one group: global dt = safety * min element dt,
//! energy balance every step, and the run-time guards (runaway, dt collapse).

use crate::energy::{EnergyLedger, EnergyTotals};
use crate::error::Fault;
use crate::group::{BodyReport, Group};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunConfig {
    pub end_time: f64,
    /// Fraction of the critical time step actually used (industry default 0.9).
    pub safety: f64,
    /// Force a constant time step (tests of the stability limit); None: automatic.
    pub fixed_dt: Option<f64>,
    /// Balance error (relative to the largest energy) that stops the run as a runaway.
    pub runaway_limit: f64,
    /// A time step below this fraction of the initial one stops the run.
    pub dt_floor_ratio: f64,
}

impl Default for RunConfig {
    fn default() -> Self {
        Self {
            end_time: 0.0,
            safety: 0.9,
            fixed_dt: None,
            runaway_limit: 0.25,
            dt_floor_ratio: 1e-3,
        }
    }
}

/// Consecutive steps above the runaway limit that stop a run.
pub const RUNAWAY_PERSIST: u32 = 3;

/// A run of one group in this process.
#[derive(Debug)]
pub struct Run {
    pub group: Group,
    pub cfg: RunConfig,
    pub ledger: EnergyLedger,
    pub reports: Vec<BodyReport>,
    pub energy: EnergyTotals,
    /// The step h_{n+1/2} the next call to `step` will take.
    pub next_dt: f64,
    pub dt0: f64,
    pub dt_min: f64,
    pub dt_max: f64,
}

/// Smallest stable dt among reports, with the body and element that set it.
pub fn critical(reports: &[BodyReport]) -> (f64, u32, usize) {
    let mut best = (f64::INFINITY, 0, 0);
    for r in reports {
        if r.stable_dt < best.0 {
            best = (r.stable_dt, r.id, r.dt_element);
        }
    }
    best
}

impl Run {
    pub fn new(mut group: Group, cfg: RunConfig) -> Result<Self, Fault> {
        let reports = group.start()?;
        let mut ledger = EnergyLedger::default();
        let energy = ledger.update(EnergyTotals::sum(reports.iter().map(|r| &r.energy)));
        let mut run = Self {
            group,
            cfg,
            ledger,
            reports,
            energy,
            next_dt: 0.0,
            dt0: 0.0,
            dt_min: f64::INFINITY,
            dt_max: 0.0,
        };
        run.next_dt = run.choose_dt()?;
        run.dt0 = run.next_dt;
        Ok(run)
    }

    fn choose_dt(&self) -> Result<f64, Fault> {
        let (crit, body, element) = critical(&self.reports);
        let dt = match self.cfg.fixed_dt {
            Some(dt) => dt,
            None => self.cfg.safety * crit,
        };
        let collapsed = self.dt0 > 0.0 && dt < self.cfg.dt_floor_ratio * self.dt0;
        if collapsed || dt.is_nan() || dt <= 0.0 {
            return Err(Fault::DtCollapse {
                step: self.group.step,
                dt,
                floor: self.cfg.dt_floor_ratio * self.dt0,
                body,
                element,
            });
        }
        Ok(dt)
    }

    pub fn time(&self) -> f64 {
        self.group.time
    }

    pub fn finished(&self) -> bool {
        self.group.time >= self.cfg.end_time * (1.0 - 1e-12)
    }

    /// Take one step; the last step is shortened to land on the end time.
    pub fn step(&mut self) -> Result<(), Fault> {
        let mut h = self.next_dt;
        let left = self.cfg.end_time - self.group.time;
        if left < h && left > 0.0 {
            h = left;
        }
        self.dt_min = self.dt_min.min(h);
        self.dt_max = self.dt_max.max(h);
        self.reports = self.group.advance(h)?;
        self.energy = self
            .ledger
            .update(EnergyTotals::sum(self.reports.iter().map(|r| &r.energy)));
        // A start from rest has O(1) relative errors for a few steps while all energies
        // are tiny; a real instability keeps growing, so require persistence.
        if self.energy.balance_error.abs() <= self.cfg.runaway_limit {
            self.ledger.over_limit = 0;
        } else {
            self.ledger.over_limit += 1;
        }
        if self.ledger.over_limit > RUNAWAY_PERSIST || self.energy.balance_error.is_nan() {
            let hot = self.reports.iter().fold(&self.reports[0], |a, b| {
                if b.hot_density > a.hot_density {
                    b
                } else {
                    a
                }
            });
            return Err(Fault::EnergyRunaway {
                step: self.group.step,
                error: self.energy.balance_error,
                limit: self.cfg.runaway_limit,
                body: hot.id,
                element: hot.hot_element,
            });
        }
        self.next_dt = self.choose_dt()?;
        Ok(())
    }

    /// Step until the end time, calling `observe` after every step.
    pub fn run(&mut self, mut observe: impl FnMut(&Run)) -> Result<(), Fault> {
        while !self.finished() {
            self.step()?;
            observe(self);
        }
        Ok(())
    }
}
