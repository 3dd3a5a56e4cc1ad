//! How the master talks to a worker: one trait for in-process and remote workers.
//!
//! `send` queues a command, `recv` returns the replies in order (exactly one per
//! command). The master sends a step to every worker before it waits for any reply,
//! so remote workers compute concurrently; a local worker executes the command inside
//! `send` (it uses the process's rayon pool, so running local workers one after the
//! other costs nothing in parallelism).

use crash_proto::{Command, Reply};
use crash_worker::Engine;
use std::collections::VecDeque;
use std::fmt;

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LinkError {
    /// The worker is gone (connection closed or reset).
    Lost(String),
    /// No reply within the timeout.
    Timeout(String),
    /// A reply that breaks the protocol.
    Protocol(String),
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkError::Lost(s) => write!(f, "disconnected: {s}"),
            LinkError::Timeout(s) => write!(f, "stopped answering: {s}"),
            LinkError::Protocol(s) => write!(f, "protocol error: {s}"),
        }
    }
}

pub trait WorkerLink {
    fn send(&mut self, cmd: Command) -> Result<(), LinkError>;
    fn recv(&mut self) -> Result<Reply, LinkError>;
    /// Where the worker is, for messages.
    fn peer(&self) -> String;
    /// Restart: set the empty worker's clock (time, step, last step length) before
    /// bodies are loaded. Only in-process workers can: the wire protocol does not
    /// carry a clock.
    fn set_clock(&mut self, _time: f64, _step: u64, _h_prev: f64) -> Result<(), LinkError> {
        Err(LinkError::Protocol(
            "this worker cannot resume a run from a checkpoint (restart needs in-process workers: crash run --restart)".into(),
        ))
    }
    /// Tell the worker to stop (best effort: it may be gone; must not block long).
    fn close(&mut self, reason: &str) {
        if self.send(Command::Shutdown(reason.into())).is_ok() {
            let _ = self.recv();
        }
    }
}

/// A worker inside this process: no network, no serialization.
#[derive(Debug, Default)]
pub struct LocalWorker {
    engine: Engine,
    replies: VecDeque<Reply>,
    index: usize,
}

impl LocalWorker {
    pub fn new(index: usize) -> Self {
        Self {
            index,
            ..Self::default()
        }
    }

    pub fn engine(&self) -> &Engine {
        &self.engine
    }
}

impl WorkerLink for LocalWorker {
    fn send(&mut self, cmd: Command) -> Result<(), LinkError> {
        let r = self.engine.handle(cmd);
        self.replies.push_back(r);
        Ok(())
    }

    fn recv(&mut self) -> Result<Reply, LinkError> {
        self.replies
            .pop_front()
            .ok_or_else(|| LinkError::Protocol("no reply pending".into()))
    }

    fn peer(&self) -> String {
        format!("in-process worker {}", self.index)
    }

    fn set_clock(&mut self, time: f64, step: u64, h_prev: f64) -> Result<(), LinkError> {
        self.engine
            .set_clock(time, step, h_prev)
            .map_err(LinkError::Protocol)
    }
}
