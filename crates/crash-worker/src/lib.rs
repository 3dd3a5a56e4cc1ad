//! crash-worker: a worker holds groups of bodies and integrates them.
//!
//! [`engine::Engine`] is the compute part (used in-process by the master's local mode);
//! [`client`] is the network part of a worker process: it dials the master's
//! `Coordinator` service and answers its commands over one bidirectional stream.
//! The `crash-worker` binary is built by the crash-master package (both binaries in one
//! package, so that tests can spawn both).

pub mod client;
pub mod engine;

pub use client::{run, WorkerError, WorkerOptions};
pub use engine::Engine;
