//! Why a distributed run stopped.

use crash_core::Fault;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum MasterError {
    #[error("invalid run input: {0}")]
    Input(String),
    /// A physical fault, exactly as a single-process run reports it.
    #[error(transparent)]
    Fault(#[from] Fault),
    /// A worker disconnected, stopped answering or broke the protocol.
    #[error("step {step}: worker {worker} ({peer}): {reason}")]
    Worker {
        step: u64,
        worker: usize,
        peer: String,
        reason: String,
    },
    /// The MEIM margin no longer covers the motion between two updates.
    #[error("step {step}: body {body} moved {moved:.3e} m in one step, more than the {allowed:.3e} m the interaction-graph margin allows (margin {margin:.3e} m, factor {factor}): contact could begin between bodies on different workers unseen; raise the contact margin or the margin factor")]
    Margin {
        step: u64,
        body: u32,
        moved: f64,
        allowed: f64,
        margin: f64,
        factor: f64,
    },
    #[error("output: {0}")]
    Sink(String),
    #[error("network: {0}")]
    Network(String),
}
