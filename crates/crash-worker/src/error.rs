//! Why a worker could not carry out a command (sent to the master as its reply's text).

use crash_core::CoreError;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum EngineError {
    #[error("a command for step {asked_step} (t = {asked_time:e} s) reached bodies at step {held_step} (t = {held_time:e} s)")]
    Clock {
        asked_step: u64,
        asked_time: f64,
        held_step: u64,
        held_time: f64,
    },
    #[error("step {step}: invalid time step {dt}")]
    Step { step: u64, dt: f64 },
    #[error("bodies arrived before the run setup (gravity, contact)")]
    NoSetup,
    #[error("body {0} is already on this worker")]
    AlreadyHeld(u32),
    #[error("{what} of body {id}, which is not on this worker")]
    NotHeld { id: u32, what: &'static str },
    #[error("cannot load: {0}")]
    Load(#[from] CoreError),
    #[error("regroup lists body {0} twice")]
    Twice(u32),
    #[error("regroup does not match the bodies held: not here {missing:?}, not placed {extra:?}")]
    Layout { missing: Vec<u32>, extra: Vec<u32> },
    #[error("a fault stopped this worker's groups")]
    Broken,
    #[error("{0} bodies were loaded but not placed in a group")]
    Unplaced(usize),
    #[error("a read-only copy of body {0} was asked for, but it is not kinematic (every degree of freedom prescribed)")]
    NotKinematic(u32),
    #[error("regroup asks for a copy of body {0}, but neither the body nor a copy of it is on this worker")]
    NoCopySource(u32),
    #[error("{0} while groups are split over workers (merge them back first)")]
    Split(&'static str),
    #[error("split group: {0}")]
    Shared(String),
}
