//! Workers that join a run after its start (issue 14 points 1 and 3).
//!
//! The master asks its `Newcomers` at step boundaries (without waiting) and, when every
//! worker was lost, waits for one up to `RunOptions::rejoin_seconds`. A newcomer gets
//! the next worker index and takes part in the next placement: a rollback's (the lost
//! worker's groups may go to it) or the regroup the master does after it joined (the
//! normal cost-based placement). `crash run`'s in-process workers have none.

use std::time::Duration;

/// Where newcomers come from (the gRPC server's admitted workers: `server::Joiner`).
pub trait Newcomers<L> {
    /// The workers admitted since the last call, to be given the indices `first`,
    /// `first + 1`, ...; when none is ready, wait up to `wait` for the first one.
    fn join(&mut self, first: usize, wait: Duration) -> Vec<L>;
}

/// A run without newcomers (in-process workers).
#[derive(Debug, Default, Clone, Copy)]
pub struct NoNewcomers;

impl<L> Newcomers<L> for NoNewcomers {
    fn join(&mut self, _first: usize, _wait: Duration) -> Vec<L> {
        Vec::new()
    }
}
