//! The study's runs go through the time loop `crash run` runs: the master loop
//! (`crash_master::Session`) over one in-process worker, observed between steps. What
//! a case measures (error against wall time) is therefore what a user of `crash run`
//! gets, master overhead included.

use super::ladder::CaseError;
use crash_core::contact::PairStats;
use crash_core::{Body, BodyBrief, Clock, Group, RunConfig};
use crash_io::FrameBody;
use crash_master::{
    BodySource, MasterError, RunInput, RunOptions, RunStats, Session, Sink, SinkError,
};
use crash_worker::LocalWorker;

/// A case's run: its bodies and settings, then (after `run`) the clock and the energy
/// balance of the finished run and the bodies of its worker.
#[derive(Debug)]
pub struct LoopRun {
    input: Option<RunInput>,
    start: Vec<Body>,
    workers: Vec<LocalWorker>,
    pub clock: Clock,
    /// Largest relative energy-balance error of the run.
    pub max_energy_error: f64,
}

/// What a case sees after each step.
#[derive(Debug)]
pub struct View<'a> {
    /// The bodies, sorted by id.
    pub bodies: Vec<&'a Body>,
    pub clock: Clock,
    contacts: Vec<PairStats>,
}

impl View<'_> {
    pub fn time(&self) -> f64 {
        self.clock.time
    }

    /// Contact statistics of the last force pass (pairs sorted).
    pub fn contact_stats(&self) -> &[PairStats] {
        &self.contacts
    }
}

/// Writes nothing: the study reads the run between steps.
#[derive(Debug, Default)]
struct Quiet;

impl Sink for Quiet {
    fn energy(&mut self, _: u64, _: f64, _: &crash_core::EnergyTotals) -> Result<(), SinkError> {
        Ok(())
    }
    fn frame_begin(&mut self, _: u64, _: f64) -> Result<(), SinkError> {
        Ok(())
    }
    fn frame_body(&mut self, _: FrameBody) -> Result<(), SinkError> {
        Ok(())
    }
    fn frame_end(&mut self) -> Result<(), SinkError> {
        Ok(())
    }
    fn finish(&mut self, _: &RunStats, _: Option<&MasterError>) -> Result<(), SinkError> {
        Ok(())
    }
}

/// Why a loop run stopped: a physical fault as the core reports it, or the loop's own.
fn case_error(e: MasterError) -> CaseError {
    match e {
        MasterError::Fault(f) => CaseError::Fault(f),
        other => CaseError::Run(other.to_string()),
    }
}

impl LoopRun {
    /// The bodies and settings of `group` (gravity, contact) run to `end_time` at the
    /// safety factor `safety`, with frames only at the start and the end.
    pub fn new(group: Group, end_time: f64, safety: f64) -> Self {
        let start = group.bodies;
        let input = RunInput {
            name: "study".into(),
            briefs: start.iter().map(BodyBrief::of).collect(),
            bodies: BodySource::Built(start.iter().cloned().map(Some).collect()),
            gravity: group.gravity,
            contact: group.contact,
            config: RunConfig {
                end_time,
                safety,
                ..RunConfig::default()
            },
            output_interval: end_time,
            scene_hash: 0,
            results: Default::default(),
        };
        Self {
            input: Some(input),
            start,
            workers: LocalWorker::many(1),
            clock: Clock::default(),
            max_energy_error: 0.0,
        }
    }

    /// The bodies: as given before the run, the worker's after it.
    pub fn bodies(&self) -> Vec<&Body> {
        if self.input.is_some() {
            self.start.iter().collect()
        } else {
            self.workers[0].engine().bodies()
        }
    }

    /// Run to the end time, calling `observe` after every step.
    pub fn run(&mut self, mut observe: impl FnMut(&View)) -> Result<(), CaseError> {
        let Some(input) = self.input.take() else {
            return Err(CaseError::Run("the case was already run".into()));
        };
        let mut sink = Quiet;
        let opts = RunOptions::default();
        let mut s =
            Session::start(input, None, &mut self.workers, &mut sink, &opts).map_err(case_error)?;
        let result = (|| {
            s.split()?;
            while !s.finished() {
                s.step(&mut sink)?;
                let Some(engine) = s.link(0).map(|w| w.engine()) else {
                    break;
                };
                observe(&View {
                    bodies: engine.bodies(),
                    clock: s.clock(),
                    contacts: engine.contact_stats(),
                });
            }
            s.finish(&mut sink)
        })();
        s.end(result.as_ref().err());
        self.clock = s.clock();
        self.max_energy_error = s.max_energy_error();
        result.map(|_| ()).map_err(case_error)
    }
}
