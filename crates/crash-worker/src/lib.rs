//! crash-worker: a worker holds groups of bodies and integrates them.
//!
//! [`engine::Engine`] is the compute part; [`local::LocalWorker`] runs it inside the
//! master's process (local mode); [`client`] is the network part of a worker process:
//! it dials the master's `Coordinator` service and answers its commands over one
//! bidirectional stream; [`probe`] asks a master's health without attaching. The
//! `crash-worker` binary is `src/main.rs`.

pub mod client;
pub mod engine;
pub mod error;
mod lane;
pub mod local;
pub mod probe;
pub mod threaded;

pub use client::{run, WorkerError, WorkerOptions};
pub use engine::Engine;
pub use error::EngineError;
pub use local::LocalWorker;
pub use threaded::{InProcess, ThreadedWorker};
