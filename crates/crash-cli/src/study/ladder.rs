//! Refinement ladders: one measured run per level, observed orders of convergence.

use super::looprun::LoopRun;
use crash_core::shapes::ElementKind;
use crash_core::{Body, CoreError, Fault, Group, Vec3};
use std::time::Instant;

/// Why a case could not be measured: its input was refused, or the run stopped.
#[derive(Debug, Clone, PartialEq)]
pub enum CaseError {
    Input(CoreError),
    Fault(Fault),
    /// The time loop stopped for a reason of its own (not a physical fault).
    Run(String),
}

impl std::fmt::Display for CaseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CaseError::Input(e) => write!(f, "input refused: {e}"),
            CaseError::Fault(e) => write!(f, "run stopped: {e}"),
            CaseError::Run(e) => write!(f, "run stopped: {e}"),
        }
    }
}

impl std::error::Error for CaseError {}

impl From<CoreError> for CaseError {
    fn from(e: CoreError) -> Self {
        CaseError::Input(e)
    }
}

impl From<Fault> for CaseError {
    fn from(e: Fault) -> Self {
        CaseError::Fault(e)
    }
}

/// One rung of a ladder: a mesh parameter (cells per side, sphere level...) and the
/// time-step safety factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Level {
    pub mesh: u32,
    pub safety: f64,
}

impl Level {
    pub fn mesh(mesh: u32) -> Self {
        Self { mesh, safety: 0.9 }
    }
}

/// What one run of a case measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    pub level: Level,
    /// Characteristic element size [m] (the abscissa of the order of convergence).
    pub h: f64,
    pub elements: usize,
    pub steps: u64,
    pub wall_s: f64,
    /// The measured quantity and its reference.
    pub value: f64,
    pub reference: f64,
    /// |value - reference| / |reference|, or the absolute value when the reference is 0.
    pub error: f64,
    /// Side results (momentum drift, energy error...), shown in the notes column.
    pub notes: Vec<(String, f64)>,
}

/// The result of a run before timing and errors are filled in.
#[derive(Debug, Clone, PartialEq)]
pub struct Raw {
    pub h: f64,
    pub elements: usize,
    pub steps: u64,
    pub value: f64,
    pub notes: Vec<(String, f64)>,
}

/// Relative error, or absolute when the reference is zero.
pub fn error_of(value: f64, reference: f64) -> f64 {
    if reference == 0.0 {
        value.abs()
    } else {
        ((value - reference) / reference).abs()
    }
}

/// Time one run of a case and compute its error.
pub fn measure(
    level: Level,
    reference: f64,
    run: impl FnOnce() -> Result<Raw, CaseError>,
) -> Result<Measurement, CaseError> {
    let start = Instant::now();
    let raw = run()?;
    let wall_s = start.elapsed().as_secs_f64();
    Ok(Measurement {
        level,
        h: raw.h,
        elements: raw.elements,
        steps: raw.steps,
        wall_s,
        value: raw.value,
        reference,
        error: error_of(raw.value, reference),
        notes: raw.notes,
    })
}

/// Observed order of convergence between successive rungs: ln(e1/e2) / ln(h1/h2).
/// None where an error is zero or the sizes are equal (a dt ladder: use `dt_orders`).
pub fn orders(ms: &[Measurement]) -> Vec<Option<f64>> {
    ms.windows(2)
        .map(|w| order((w[0].h, w[0].error), (w[1].h, w[1].error)))
        .collect()
}

/// Orders of a time-step ladder (same mesh, safety factors as the abscissa).
pub fn dt_orders(ms: &[Measurement]) -> Vec<Option<f64>> {
    ms.windows(2)
        .map(|w| {
            order(
                (w[0].level.safety, w[0].error),
                (w[1].level.safety, w[1].error),
            )
        })
        .collect()
}

fn order(a: (f64, f64), b: (f64, f64)) -> Option<f64> {
    let p = (a.1 / b.1).ln() / (a.0 / b.0).ln();
    (a.1 > 0.0 && b.1 > 0.0 && a.0 != b.0 && p.is_finite()).then_some(p)
}

/// A run of `group`'s bodies through the time loop `crash run` runs, at the level's
/// safety factor.
pub fn driver(group: Group, end_time: f64, safety: f64) -> Result<LoopRun, CaseError> {
    Ok(LoopRun::new(group, end_time, safety))
}

/// A group of bodies without gravity.
pub fn group(bodies: Vec<Body>) -> Group {
    Group::new(bodies, Vec3::zeros())
}

pub fn kind_name(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Tri => "tri",
        ElementKind::Quad => "quad",
    }
}
