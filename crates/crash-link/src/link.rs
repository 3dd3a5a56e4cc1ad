//! How the master talks to a worker: one trait for in-process and remote workers.
//!
//! `send` queues a command, `recv` returns the replies in order (exactly one per
//! command). The master sends a step to every worker before it waits for any reply,
//! so remote workers compute concurrently.

use crate::command::{Command, Reply};
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum LinkError {
    /// The worker is gone (connection closed or reset).
    #[error("disconnected: {0}")]
    Lost(String),
    /// No reply within the timeout.
    #[error("stopped answering: no reply within {seconds:.1} s")]
    Timeout { seconds: f64 },
    /// No heartbeat within the heartbeat timeout (frozen, stopped, host gone).
    #[error("stopped answering: no heartbeat for {seconds:.1} s")]
    Silent { seconds: f64 },
    /// A reply that breaks the protocol.
    #[error("protocol error: {0}")]
    Protocol(String),
    /// The worker could not carry out a command (its own words).
    #[error("refused a command: {0}")]
    Refused(String),
    /// The worker reported what cannot be true (a non-finite value, a body it does not
    /// hold, a box inside out, ...): it is dropped as a lost one would be, since
    /// nothing it says can be trusted any more.
    #[error("reported what cannot be true: {0}")]
    Implausible(String),
}

pub trait WorkerLink {
    fn send(&mut self, cmd: Command) -> Result<(), LinkError>;
    fn recv(&mut self) -> Result<Reply, LinkError>;
    /// Where the worker is, for messages.
    fn peer(&self) -> String;
    /// Whether the worker holds the definition of body `id` (a body moving there then
    /// travels as its state only).
    fn has_definition(&self, id: u32) -> bool;
    /// Where the worker takes direct halo connections from the other workers
    /// (host:port; None: nowhere, its part states are relayed by the master).
    fn halo_address(&self) -> Option<String> {
        None
    }
    /// Time this link spent encoding commands and decoding replies since the last call
    /// [ns] (a part of the barrier; 0 for in-process links).
    fn take_codec_ns(&mut self) -> u64 {
        0
    }
    /// Tell the worker to stop (best effort: it may be gone; must not block long).
    fn close(&mut self, reason: &str) {
        if self.send(Command::Shutdown(reason.into())).is_ok() {
            let _ = self.recv();
        }
    }
    /// Drop a worker that was lost (its replies are no longer read): tell it why if it
    /// can still hear, without waiting for anything.
    fn abandon(&mut self, reason: &str) {
        let _ = self.send(Command::Shutdown(reason.into()));
    }
}

impl LinkError {
    /// The worker is gone, frozen or caught reporting the impossible (as opposed to a
    /// worker that answered a command wrongly): the run can continue without it.
    pub fn is_loss(&self) -> bool {
        matches!(
            self,
            LinkError::Lost(_)
                | LinkError::Timeout { .. }
                | LinkError::Silent { .. }
                | LinkError::Implausible(_)
        )
    }
}
