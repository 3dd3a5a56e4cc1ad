//! Heartbeats: the last sign of life of every admitted worker.
//!
//! A worker beats from a thread of its own on a connection of its own
//! (crash-worker's client), so a long step does not silence it. The beat carries the
//! session token its Welcome gave it (32 random bytes, compared in constant time), so a
//! stranger cannot keep a dead worker "alive". The master's link reads the age of the
//! last beat while it waits for a reply (`RemoteWorker::recv`): the beats are handled
//! by the master's runtime, which without the step lane runs only while the master
//! waits (with it, on a thread of its own), so silence is
//! counted from the later of the last beat and the start of the wait (time the master
//! spent busy elsewhere never counts against a worker).

use std::collections::BTreeMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};
use tonic::Status;

/// Default silence after which a worker is declared lost.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(5);

/// How often a worker beats for a given timeout: five beats per timeout, between
/// 50 ms and 1 s.
pub fn interval_for(timeout: Duration) -> Duration {
    (timeout / 5).clamp(Duration::from_millis(50), Duration::from_secs(1))
}

#[derive(Debug)]
struct Slot {
    token: [u8; crash_link::auth::NONCE_LEN],
    last: Option<Instant>,
}

/// Tokens and last beats by worker index.
#[derive(Debug, Default)]
pub struct Beats {
    slots: Mutex<BTreeMap<u32, Slot>>,
}

impl Beats {
    /// A fresh token for worker `index` (replaces an earlier one).
    pub fn register(&self, index: u32) -> Result<Vec<u8>, crash_link::SecretError> {
        let token = crash_link::auth::nonce()?;
        if let Ok(mut s) = self.slots.lock() {
            s.insert(index, Slot { token, last: None });
        }
        Ok(token.to_vec())
    }

    /// A beat: NOT_FOUND for a worker the run no longer counts (the worker stops
    /// beating), UNAUTHENTICATED for a wrong token.
    pub fn beat(&self, index: u32, token: &[u8]) -> Result<(), Status> {
        let mut slots = self
            .slots
            .lock()
            .map_err(|_| Status::internal("heartbeat table poisoned"))?;
        let Some(slot) = slots.get_mut(&index) else {
            return Err(Status::not_found(format!(
                "worker {index} is not part of this run (any more)"
            )));
        };
        if !same(&slot.token, token) {
            return Err(Status::unauthenticated("wrong session token"));
        }
        slot.last = Some(Instant::now());
        Ok(())
    }

    /// Whether `token` is worker `index`'s session token (constant time; no beat).
    pub fn holds(&self, index: u32, token: &[u8]) -> bool {
        self.slots
            .lock()
            .ok()
            .and_then(|s| s.get(&index).map(|slot| same(&slot.token, token)))
            .unwrap_or(false)
    }

    /// When worker `index` last beat (None: never, or unknown).
    pub fn last(&self, index: u32) -> Option<Instant> {
        self.slots.lock().ok()?.get(&index)?.last
    }

    /// Forget worker `index` (it was dropped): its next beat gets NOT_FOUND.
    pub fn revoke(&self, index: u32) {
        if let Ok(mut s) = self.slots.lock() {
            s.remove(&index);
        }
    }
}

/// Constant-time comparison (no early exit on the first differing byte).
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // a test panics on failure
mod tests {
    use super::*;

    #[test]
    fn only_the_registered_token_counts_and_a_revoked_worker_is_not_found() {
        let b = Beats::default();
        let t = b.register(1).unwrap();
        assert!(b.last(1).is_none());
        let mut wrong = t.clone();
        wrong[0] ^= 1;
        assert_eq!(
            b.beat(1, &wrong).unwrap_err().code(),
            tonic::Code::Unauthenticated
        );
        assert_eq!(
            b.beat(1, &t[..31]).unwrap_err().code(),
            tonic::Code::Unauthenticated
        );
        assert!(b.last(1).is_none());
        b.beat(1, &t).unwrap();
        assert!(b.last(1).is_some());
        assert_eq!(b.beat(2, &t).unwrap_err().code(), tonic::Code::NotFound);
        b.revoke(1);
        assert_eq!(b.beat(1, &t).unwrap_err().code(), tonic::Code::NotFound);
    }

    #[test]
    fn a_worker_beats_five_times_per_timeout_within_bounds() {
        assert_eq!(interval_for(Duration::from_secs(5)), Duration::from_secs(1));
        assert_eq!(
            interval_for(Duration::from_secs(1)),
            Duration::from_millis(200)
        );
        assert_eq!(
            interval_for(Duration::from_millis(10)),
            Duration::from_millis(50)
        );
        assert_eq!(
            interval_for(Duration::from_secs(60)),
            Duration::from_secs(1)
        );
    }
}
