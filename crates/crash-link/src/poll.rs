//! A bounded busy wait before a blocking one, for the waits on a step's critical path.
//!
//! Why: a process that blocks in a read is woken by the kernel when the message comes,
//! and on a virtual machine that wake-up goes through the hypervisor: on the project's
//! 2-vCPU VMs a cross-vCPU wake costs 25-35 us (a blocking pipe round trip between two
//! pinned processes 53 us, a spinning one 2 us; docs/performance.md, session 26), and a
//! split step has several on its critical path. A worker that has sent its reply polls
//! its socket for a while instead, giving the CPU away between tries (`sched_yield`),
//! so a process woken on the same CPU (the master, two processes on two cores) runs at
//! once; the next command then finds the worker running. When the budget runs out the
//! wait blocks as before. MPI libraries busy-wait for the same reason.

use std::time::{Duration, Instant};

/// The workers' default budget (`crash-worker --poll-us`): longer than the master's
/// work between two steps (tens of microseconds), short enough that a master busy for
/// longer (a frame, a migration) costs a worker at most this much CPU per wait.
pub const DEFAULT_BUDGET: Duration = Duration::from_micros(1000);

/// Try `once` until it gives a value or `budget` has passed, yielding the CPU between
/// tries. `Ok(None)`: the budget ran out (the caller then blocks); a zero budget tries
/// nothing.
pub fn poll_for<T, E>(
    budget: Duration,
    mut once: impl FnMut() -> Result<Option<T>, E>,
) -> Result<Option<T>, E> {
    if budget.is_zero() {
        return Ok(None);
    }
    let until = Instant::now() + budget;
    loop {
        if let Some(v) = once()? {
            return Ok(Some(v));
        }
        if Instant::now() >= until {
            return Ok(None);
        }
        std::thread::yield_now();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A value that comes within the budget is returned; none after it; a zero budget
    /// never calls the probe.
    #[test]
    fn polling_returns_what_comes_within_the_budget_and_nothing_after() {
        let mut n = 0;
        let got: Result<Option<u32>, ()> = poll_for(Duration::from_secs(5), || {
            n += 1;
            Ok((n == 3).then_some(7))
        });
        assert_eq!(got, Ok(Some(7)));
        let t = Instant::now();
        let none: Result<Option<u32>, ()> = poll_for(Duration::from_millis(2), || Ok(None));
        assert_eq!(none, Ok(None));
        assert!(t.elapsed() >= Duration::from_millis(2));
        let mut called = false;
        let zero: Result<Option<u32>, ()> = poll_for(Duration::ZERO, || {
            called = true;
            Ok(Some(1))
        });
        assert_eq!(zero, Ok(None));
        assert!(!called);
        let err: Result<Option<u32>, &str> = poll_for(Duration::from_secs(5), || Err("closed"));
        assert_eq!(err, Err("closed"));
    }
}
