//! What a checkpoint of the master loop holds: everything the rest of the run depends
//! on. The clock (step, time, last step), the next and first step lengths, the energy
//! ledger, the MEIM edges with their split timers, the frame schedule, the run
//! statistics and every body's state (gathered from the workers; definitions come from
//! the scene). What is left out never changes results: contact search caches (rebuilt
//! lazily), the Verlet list of the level-i search (its result equals a full search),
//! measured group costs and the placement (a group computes the same bits on any
//! worker), so a run resumes on any number of workers.

use crate::error::MasterError;
use crate::meim::Interaction;
use crate::stats::RunStats;
use crash_core::{BodyState, Clock, EnergyLedger, KinematicWork};
use serde::{Deserialize, Serialize};

/// The master loop's state after a step.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MasterCheckpoint {
    /// Hash of the scene input: a checkpoint only continues the run of its own scene.
    pub scene_hash: u64,
    /// The run's clock after the checkpoint's step.
    pub clock: Clock,
    /// The step the loop takes next (before shortening to the end time).
    pub next_dt: f64,
    /// The first step (reference of the dt-collapse floor).
    pub dt0: f64,
    pub ledger: EnergyLedger,
    /// Contact work on the kinematic bodies so far.
    pub kinematic_work: KinematicWork,
    /// MEIM edges (a < b) and their timers.
    pub edges: Vec<((u32, u32), Interaction)>,
    /// Output schedule: frames due so far and the step of the last frame.
    pub frames: u64,
    pub last_frame_step: Option<u64>,
    /// Statistics so far (wall time: up to the checkpoint).
    pub stats: RunStats,
    /// Every body's state, sorted by id.
    pub states: Vec<(u32, BodyState)>,
}

impl MasterCheckpoint {
    /// Whether this checkpoint can continue the run of the scene with `scene_hash` to
    /// `end_time`. Checked before the run directory is reopened (a reopen drops the
    /// rows after the checkpoint): an end time before the checkpoint's time would
    /// otherwise end the run at once with a final frame and summary as if it had run.
    pub fn check_continues(&self, scene_hash: u64, end_time: f64) -> Result<(), MasterError> {
        if self.scene_hash != scene_hash {
            return Err(MasterError::Input(format!(
                "the checkpoint belongs to another scene (scene hash {:016x}, this scene {scene_hash:016x}); continue with the scene file of the original run",
                self.scene_hash
            )));
        }
        let c = self.clock;
        if end_time < c.time {
            return Err(MasterError::Input(format!(
                "the end time {end_time:.6e} s is before the checkpoint's time {:.6e} s (step {}): give an end time after it (--end-time) or continue from an earlier checkpoint",
                c.time, c.step
            )));
        }
        Ok(())
    }
}
