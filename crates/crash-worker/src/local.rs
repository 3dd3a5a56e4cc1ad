//! A worker inside the master's process: no network, no serialization. Bodies move
//! between in-process workers as they are (definitions shared behind their Arc).

use crate::engine::Engine;
use crash_link::{Command, LinkError, Reply, WorkerLink};
use std::collections::VecDeque;

/// An in-process worker: executes each command inside `send`, on the caller's thread
/// and rayon pool, and queues the reply (crash run's last worker, computing while the
/// threaded ones do, `threaded.rs`; the study's one worker, read between steps).
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

    /// `n` in-process workers (at least one).
    pub fn many(n: usize) -> Vec<Self> {
        (0..n.max(1)).map(Self::new).collect()
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

    fn has_definition(&self, id: u32) -> bool {
        self.engine.has_definition(id)
    }
}
