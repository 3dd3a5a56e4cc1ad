//! Why a distributed run stopped.

use crash_core::Fault;
use crash_link::LinkError;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum MasterError {
    #[error("invalid run input: {0}")]
    Input(String),
    /// A physical fault, exactly as a single-process run reports it.
    #[error(transparent)]
    Fault(#[from] Fault),
    /// A worker disconnected, stopped answering, broke the protocol or refused a command.
    #[error("step {step}: worker {worker} ({peer}): {reason}")]
    Worker {
        step: u64,
        worker: usize,
        peer: String,
        reason: LinkError,
    },
    /// Fewer bodies came back than the workers hold.
    #[error("step {step}: {got} of {expected} {what} came back from the workers")]
    Incomplete {
        step: u64,
        what: &'static str,
        got: usize,
        expected: usize,
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
    /// The holders of a split group could not exchange their part states directly:
    /// the run goes back to its last checkpoint and relays them through the master.
    #[error("step {step}: worker {worker} could not exchange halos with the other workers directly ({reason}); relaying them through the master from now on")]
    DirectHalo {
        step: u64,
        worker: usize,
        reason: String,
    },
    /// Every worker was lost: the run cannot continue here.
    #[error("step {step}: every worker was lost; the run stopped and its last checkpoint (step {checkpoint}) was kept (crash-master: OUT/restart.ckp): continue with --resume and new workers")]
    NoWorkers { step: u64, checkpoint: u64 },
    #[error("output: {0}")]
    Sink(String),
    #[error("network: {0}")]
    Network(String),
    /// Stopped on request (SIGTERM, SIGINT) after a complete step: a checkpoint and
    /// the final frame of that step were written.
    #[error(
        "interrupted at step {step} (t = {time:.6e} s) by a signal; a restart file was written"
    )]
    Interrupted { step: u64, time: f64 },
}

/// What a sink's writers may fail with (boxed: each sink has its own errors).
pub type SinkError = Box<dyn std::error::Error + Send + Sync>;

impl MasterError {
    /// An output error (the sink's own error type is boxed).
    pub fn sink(e: SinkError) -> Self {
        MasterError::Sink(e.to_string())
    }
}
