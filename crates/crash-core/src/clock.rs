//! The one step clock of a run. The loop that drives a run (the master, or the
//! single-process driver) owns it; every step command and every checkpoint carries it.
//! Groups and workers keep no time of their own, so a run resumes from any checkpoint
//! on any set of workers.

use crate::integrate::StepClock;
use serde::{Deserialize, Serialize};

/// Where a run stands: steps taken, time reached and the length of the last step
/// (h_{n-1/2}, needed by the central difference of the next step; 0 at the start).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Clock {
    pub step: u64,
    /// t_n [s].
    pub time: f64,
    /// h_{n-1/2} [s].
    pub last_dt: f64,
}

impl Clock {
    /// The integration data of the step of length `h` that starts here.
    pub fn step_of(&self, h: f64) -> StepClock {
        StepClock {
            t: self.time,
            h_prev: self.last_dt,
            h,
            step: self.step,
        }
    }

    /// The clock after a step of length `h`.
    pub fn after(&self, h: f64) -> Clock {
        Clock {
            step: self.step + 1,
            time: self.time + h,
            last_dt: h,
        }
    }

    /// Bitwise equality (a clock that differs in the last bit is another clock).
    pub fn same_as(&self, o: &Clock) -> bool {
        self.step == o.step
            && self.time.to_bits() == o.time.to_bits()
            && self.last_dt.to_bits() == o.last_dt.to_bits()
    }
}
