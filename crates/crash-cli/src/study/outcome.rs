//! What a stability cell did: ran stably (with its energy error), stopped with a
//! diagnostic (input refused, or a run-time fault), or blew up silently (the one
//! outcome that must never happen).

use crash_core::contact::PairStats;
use crash_core::EnergyTotals;
use crash_io::FrameBody;
use crash_master::{run_with, MasterError, RunInput, RunOptions, RunStats, Sink, SinkError};
use crash_worker::LocalWorker;

/// Final |energy-balance error| above which a run that ended without a fault counts as
/// a silent blow-up.
pub const SILENT_ERROR: f64 = 0.5;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Refused before the run (scene, mesh, material or overlap check).
    Input,
    /// Stopped by a run-time guard (`Fault`) or another master error.
    Run,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    Stable {
        /// Largest relative energy-balance error of the run.
        max_error: f64,
        /// Largest penetration / thickness of the thinner body seen in any contact.
        max_penetration: f64,
        steps: u64,
        /// Energy error above the scene's energy limit or penetration above crash-io's
        /// limit (`crash run` warns and exits with 4).
        over_limit: bool,
    },
    Stopped {
        stage: Stage,
        message: String,
        /// Steps taken before the stop (0 for input).
        steps: u64,
    },
    SilentBlowUp {
        reason: String,
    },
}

impl Outcome {
    pub fn is_silent_blow_up(&self) -> bool {
        matches!(self, Outcome::SilentBlowUp { .. })
    }

    pub fn short(&self) -> &'static str {
        match self {
            Outcome::Stable {
                over_limit: false, ..
            } => "stable",
            Outcome::Stable {
                over_limit: true, ..
            } => "stable, warned",
            Outcome::Stopped {
                stage: Stage::Input,
                ..
            } => "refused at input",
            Outcome::Stopped {
                stage: Stage::Run, ..
            } => "stopped (fault)",
            Outcome::SilentBlowUp { .. } => "SILENT BLOW-UP",
        }
    }
}

/// A pass-through check of a completed run: no node of `body` over the square
/// |x|, |y| < `half_size` may end below the plane z = `z` (the plate's mid-surface).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassGuard {
    pub body: u32,
    pub half_size: f64,
    pub z: f64,
}

/// Watches every energy row and every frame for non-finite numbers.
#[derive(Debug, Default)]
struct Watch {
    non_finite: Option<String>,
    max_penetration: f64,
    last: Option<EnergyTotals>,
    steps: u64,
    /// Step of the frame being received.
    frame_step: u64,
    guard: Option<PassGuard>,
    /// Lowest node of the guarded body over the square in the last frame.
    lowest: f64,
}

impl Watch {
    fn flag(&mut self, what: String) {
        self.non_finite.get_or_insert(what);
    }
}

impl Sink for Watch {
    fn energy(&mut self, step: u64, _time: f64, t: &EnergyTotals) -> Result<(), SinkError> {
        let all = [
            t.kinetic,
            t.internal,
            t.hourglass,
            t.contact,
            t.damping,
            t.external,
            t.balance_error,
        ];
        if all.iter().any(|v| !v.is_finite()) {
            self.flag(format!("non-finite energy at step {step}"));
        }
        self.last = Some(*t);
        self.steps = step;
        Ok(())
    }

    fn contact_stats(&mut self, step: u64, _time: f64, s: &[PairStats]) -> Result<(), SinkError> {
        for p in s {
            if !(p.max_penetration_ratio.is_finite() && p.normal_force.is_finite()) {
                self.flag(format!("non-finite contact statistics at step {step}"));
            }
            self.max_penetration = self.max_penetration.max(p.max_penetration_ratio);
        }
        Ok(())
    }

    fn frame_begin(&mut self, step: u64, _time: f64) -> Result<(), SinkError> {
        self.frame_step = step;
        Ok(())
    }

    fn frame_body(&mut self, b: FrameBody) -> Result<(), SinkError> {
        let finite = |v: &[crash_core::Vec3]| v.iter().all(|p| p.iter().all(|c| c.is_finite()));
        if !(finite(&b.x) && finite(&b.v) && finite(&b.w)) {
            let step = self.frame_step;
            self.flag(format!("non-finite state of body {} at step {step}", b.id));
        }
        if let Some(g) = self.guard.filter(|g| g.body == b.id) {
            self.lowest =
                b.x.iter()
                    .filter(|p| p.x.abs() < g.half_size && p.y.abs() < g.half_size)
                    .map(|p| p.z - g.z)
                    .fold(f64::INFINITY, f64::min);
        }
        Ok(())
    }

    fn frame_end(&mut self) -> Result<(), SinkError> {
        Ok(())
    }

    fn finish(&mut self, _stats: &RunStats, _error: Option<&MasterError>) -> Result<(), SinkError> {
        Ok(())
    }
}

/// Run `input` through the master loop (one in-process worker, like `crash run`) and
/// classify what happened.
pub fn run_and_classify(input: RunInput, energy_limit: f64) -> Outcome {
    run_and_classify_guarded(input, energy_limit, None)
}

/// The same with a pass-through check of the final state: a completed run with a node
/// on the far side of the plate is a silent failure.
pub fn run_and_classify_guarded(
    input: RunInput,
    energy_limit: f64,
    guard: Option<PassGuard>,
) -> Outcome {
    let mut watch = Watch {
        guard,
        lowest: f64::INFINITY,
        ..Watch::default()
    };
    let result = run_with(
        input,
        &mut LocalWorker::many(1),
        &mut watch,
        &RunOptions::default(),
    );
    classify(result, &watch, energy_limit)
}

fn classify(result: Result<RunStats, MasterError>, w: &Watch, energy_limit: f64) -> Outcome {
    match result {
        Err(e) => Outcome::Stopped {
            stage: match e {
                MasterError::Input(_) => Stage::Input,
                _ => Stage::Run,
            },
            message: e.to_string(),
            steps: w.steps,
        },
        Ok(stats) => {
            if let Some(what) = &w.non_finite {
                return Outcome::SilentBlowUp {
                    reason: what.clone(),
                };
            }
            let last = w.last.map_or(f64::NAN, |t| t.balance_error);
            if !(stats.max_energy_error.is_finite() && last.is_finite()) {
                return Outcome::SilentBlowUp {
                    reason: "non-finite energy-balance error".into(),
                };
            }
            if w.guard.is_some() && w.lowest < 0.0 {
                return Outcome::SilentBlowUp {
                    reason: format!(
                        "finished with a node {:.3e} m below the plate's mid-surface: a silent pass-through",
                        -w.lowest
                    ),
                };
            }
            if last.abs() > SILENT_ERROR {
                return Outcome::SilentBlowUp {
                    reason: format!(
                        "finished with an energy-balance error of {:.1}% and no fault",
                        100.0 * last.abs()
                    ),
                };
            }
            Outcome::Stable {
                max_error: stats.max_energy_error,
                max_penetration: w.max_penetration,
                steps: stats.steps,
                over_limit: stats.max_energy_error > energy_limit
                    || w.max_penetration > crash_io::summary::PENETRATION_LIMIT,
            }
        }
    }
}

/// An input refused before the run.
pub fn refused(message: impl std::fmt::Display) -> Outcome {
    Outcome::Stopped {
        stage: Stage::Input,
        message: message.to_string(),
        steps: 0,
    }
}
