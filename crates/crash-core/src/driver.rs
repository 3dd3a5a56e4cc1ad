//! The in-process time loop over one group: global dt = safety * min element dt,
//! energy balance every step, and the run-time guards (runaway, dt collapse).

use crate::clock::Clock;
use crate::energy::{EnergyLedger, EnergyTotals, KinematicWork};
use crate::error::Fault;
use crate::group::{BodyReport, Group};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunConfig {
    pub end_time: f64,
    /// Fraction of the critical time step actually used (industry default 0.9).
    pub safety: f64,
    /// Force a constant time step (tests of the stability limit); None: automatic.
    pub fixed_dt: Option<f64>,
    /// The scene's one energy-balance limit (`energy_limit`): the run's energy figure
    /// (`EnergyLedger::max_error`) above it for more than `RUNAWAY_PERSIST` steps stops
    /// the run; the indicators and the warning judge the same figure against it.
    pub energy_limit: f64,
    /// A time step below this fraction of the initial one stops the run.
    pub dt_floor_ratio: f64,
}

impl Default for RunConfig {
    fn default() -> Self {
        Self {
            end_time: 0.0,
            safety: 0.9,
            fixed_dt: None,
            energy_limit: DEFAULT_ENERGY_LIMIT,
            dt_floor_ratio: 1e-3,
        }
    }
}

/// The step to take: `next_dt`, or what is `left` to the end time when that is shorter
/// (then `true`: the record of a shortened last step enters neither dt_min/dt_max nor the
/// run's energy figure, see `EnergyLedger::record`). The same rule in every loop.
pub fn step_length(next_dt: f64, left: f64) -> (f64, bool) {
    if left < next_dt && left > 0.0 {
        (left, true)
    } else {
        (next_dt, false)
    }
}

/// Consecutive steps above the energy limit that stop a run.
pub const RUNAWAY_PERSIST: u32 = 3;

/// The energy-balance limit when a scene gives none (`energy_limit` of the scene).
pub const DEFAULT_ENERGY_LIMIT: f64 = 0.05;

/// A run of one group in this process.
#[derive(Debug)]
pub struct Run {
    pub group: Group,
    /// The run's one clock.
    pub clock: Clock,
    pub cfg: RunConfig,
    pub ledger: EnergyLedger,
    pub reports: Vec<BodyReport>,
    pub energy: EnergyTotals,
    /// The step h_{n+1/2} the next call to `step` will take.
    pub next_dt: f64,
    pub dt0: f64,
    pub dt_min: f64,
    pub dt_max: f64,
    /// Contact work on the kinematic bodies so far (into their reports' energy).
    pub kinematic: KinematicWork,
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

/// The global time step: safety x the smallest stable dt of the reports (or the fixed dt);
/// a step below `dt_floor_ratio` of the first one (`dt0`, 0 before it is known) is a fault.
/// The same rule in every mode (single group, local workers, remote workers).
pub fn choose_dt(
    cfg: &RunConfig,
    reports: &[BodyReport],
    dt0: f64,
    step: u64,
) -> Result<f64, Fault> {
    let (crit, body, element) = critical(reports);
    let dt = match cfg.fixed_dt {
        Some(dt) => dt,
        None => cfg.safety * crit,
    };
    let collapsed = dt0 > 0.0 && dt < cfg.dt_floor_ratio * dt0;
    if collapsed || dt.is_nan() || dt <= 0.0 {
        return Err(Fault::DtCollapse {
            step,
            dt,
            floor: cfg.dt_floor_ratio * dt0,
            body,
            element,
        });
    }
    Ok(dt)
}

/// The energy guard: the run's energy-balance figure (`EnergyTotals::run_error`, the
/// largest imbalance over the largest energy, the figure the indicators and the warning
/// judge) above the scene's `energy_limit` for more than `RUNAWAY_PERSIST` consecutive
/// steps, or NaN, stops the run naming the most strained element. The persistence lets
/// the first steps of a start from rest pass, when every energy is near zero and the
/// largest energy still grows faster than the imbalance.
pub fn check_runaway(
    cfg: &RunConfig,
    ledger: &mut EnergyLedger,
    energy: &EnergyTotals,
    reports: &[BodyReport],
    step: u64,
) -> Result<(), Fault> {
    if energy.run_error.abs() <= cfg.energy_limit {
        ledger.over_limit = 0;
    } else {
        ledger.over_limit += 1;
    }
    if ledger.over_limit > RUNAWAY_PERSIST
        || energy.balance_error.is_nan()
        || energy.run_error.is_nan()
    {
        let hot = reports.iter().fold(None::<&BodyReport>, |a, b| match a {
            Some(a) if a.hot_density >= b.hot_density => Some(a),
            _ => Some(b),
        });
        return Err(Fault::EnergyRunaway {
            step,
            error: energy.run_error,
            limit: cfg.energy_limit,
            body: hot.map_or(0, |h| h.id),
            element: hot.map_or(0, |h| h.hot_element),
        });
    }
    Ok(())
}

impl Run {
    pub fn new(mut group: Group, cfg: RunConfig) -> Result<Self, Fault> {
        let mut reports = group.start()?;
        let mut kinematic = KinematicWork::new(
            group
                .bodies
                .iter()
                .filter(|b| b.def.kinematic)
                .map(|b| (b.def.id, b.def.programs.clone(), b.def.curves.clone())),
        );
        kinematic.add(group.contact_stats());
        kinematic.apply(&mut reports);
        let mut ledger = EnergyLedger::default();
        let energy = ledger.update(EnergyTotals::sum(reports.iter().map(|r| &r.energy)));
        let mut run = Self {
            group,
            clock: Clock::default(),
            cfg,
            ledger,
            reports,
            energy,
            next_dt: 0.0,
            dt0: 0.0,
            dt_min: f64::INFINITY,
            dt_max: 0.0,
            kinematic,
        };
        run.next_dt = run.choose_dt()?;
        run.dt0 = run.next_dt;
        Ok(run)
    }

    fn choose_dt(&self) -> Result<f64, Fault> {
        choose_dt(&self.cfg, &self.reports, self.dt0, self.clock.step)
    }

    pub fn time(&self) -> f64 {
        self.clock.time
    }

    pub fn finished(&self) -> bool {
        self.clock.time >= self.cfg.end_time * (1.0 - 1e-12)
    }

    /// Take one step; the last step is shortened to land on the end time.
    pub fn step(&mut self) -> Result<(), Fault> {
        let (h, short) = step_length(self.next_dt, self.cfg.end_time - self.clock.time);
        if !short {
            self.dt_min = self.dt_min.min(h);
            self.dt_max = self.dt_max.max(h);
        }
        self.reports = self.group.advance(&self.clock, h)?;
        self.kinematic.settle(&self.clock, h);
        self.kinematic.add(self.group.contact_stats());
        self.kinematic.apply(&mut self.reports);
        self.clock = self.clock.after(h);
        self.energy = self.ledger.record(
            EnergyTotals::sum(self.reports.iter().map(|r| &r.energy)),
            !short,
        );
        check_runaway(
            &self.cfg,
            &mut self.ledger,
            &self.energy,
            &self.reports,
            self.clock.step,
        )?;
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
