//! Checkpoint and restart of the master loop. A checkpoint holds everything the rest
//! of the run depends on: every body (whole state, gathered from the workers), the
//! clock (step, time, last step, next step, first step), the energy ledger, the MEIM
//! edges with their split timers, the frame schedule and the run statistics. What is
//! left out never changes results: contact search caches (rebuilt lazily), the Verlet
//! list of the level-i search (its result equals a full search), measured group costs
//! and the placement (a group computes the same bits on any worker).

use super::Master;
use crate::error::MasterError;
use crate::link::WorkerLink;
use crate::meim::{Interaction, Meim};
use crate::stats::RunStats;
use crash_core::{Body, EnergyLedger, Vec3};
use crash_proto::{Command, Reply, Setup};
use serde::{Deserialize, Serialize};

/// The master loop's state after a step.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MasterCheckpoint {
    /// Hash of the scene input: a checkpoint only continues the run of its own scene.
    pub scene_hash: u64,
    /// Steps taken and the time reached.
    pub step: u64,
    pub time: f64,
    /// Length of the last step (the groups' h_prev).
    pub h_prev: f64,
    /// The step the loop takes next (before shortening to the end time).
    pub next_dt: f64,
    /// The first step (reference of the dt-collapse floor).
    pub dt0: f64,
    pub ledger: EnergyLedger,
    /// MEIM edges (a < b) and their timers.
    pub edges: Vec<((u32, u32), Interaction)>,
    /// Output schedule: frames due so far and the step of the last frame.
    pub frames: u64,
    pub last_frame_step: Option<u64>,
    /// Statistics so far (wall time: up to the checkpoint).
    pub stats: RunStats,
    /// Every body, sorted by id.
    pub bodies: Vec<Body>,
}

impl<L: WorkerLink> Master<'_, L> {
    /// Steps taken so far.
    pub(crate) fn steps(&self) -> u64 {
        self.step
    }

    /// The state after the current step (bodies gathered from the workers).
    pub(crate) fn checkpoint(&mut self) -> Result<MasterCheckpoint, MasterError> {
        let bodies = self.snapshot()?;
        Ok(MasterCheckpoint {
            scene_hash: self.scene_hash,
            step: self.step,
            time: self.time,
            h_prev: self.h_prev,
            next_dt: self.next_dt,
            dt0: self.dt0,
            ledger: self.ledger.clone(),
            edges: self.meim.edge_states(),
            frames: self.frames,
            last_frame_step: self.last_frame_step,
            stats: self.stats.clone(),
            bodies,
        })
    }

    /// Continue from a checkpoint instead of `start`: restore the loop's state, place
    /// the restored groups and load the bodies onto workers whose clocks are set to the
    /// checkpoint's. Nothing is written to the sink (its files already hold the rows
    /// and frames up to the checkpoint).
    pub(crate) fn resume(
        &mut self,
        ck: MasterCheckpoint,
        gravity: Vec3,
    ) -> Result<(), MasterError> {
        if ck.scene_hash != self.scene_hash {
            return Err(MasterError::Input(format!(
                "the checkpoint belongs to another scene (scene hash {:016x}, this scene {:016x})",
                ck.scene_hash, self.scene_hash
            )));
        }
        let ids: Vec<u32> = self.info.iter().map(|i| i.id).collect();
        let ck_ids: Vec<u32> = ck.bodies.iter().map(|b| b.id).collect();
        if ck_ids != ids {
            return Err(MasterError::Input(format!(
                "the checkpoint holds bodies {ck_ids:?}, the scene {ids:?}"
            )));
        }
        if !(ck.time.is_finite() && ck.next_dt > 0.0 && ck.next_dt.is_finite()) {
            return Err(MasterError::Input(format!(
                "the checkpoint's clock is invalid (t = {}, next dt = {})",
                ck.time, ck.next_dt
            )));
        }
        self.step = ck.step;
        self.time = ck.time;
        self.h_prev = ck.h_prev;
        self.next_dt = ck.next_dt;
        self.dt0 = ck.dt0;
        self.ledger = ck.ledger;
        self.meim = Meim::restore(&ids, self.opts.split_after, &ck.edges);
        self.frames = ck.frames;
        self.last_frame_step = ck.last_frame_step;
        self.stats = ck.stats;
        // the Verlet list starts empty: the first update does a full search
        let groups = self.owned_groups();
        let placement = self.place(&groups, true);
        let nw = self.links.len();
        let mut per_worker: Vec<Vec<Body>> = (0..nw).map(|_| Vec::new()).collect();
        for b in ck.bodies {
            let Some(i) = self.index(b.id) else { continue };
            self.worker_of[i] = Some(placement[i]);
            per_worker[placement[i]].push(b);
        }
        self.layout = self.layouts(&groups, &placement);
        for w in 0..nw {
            let (t, s, h) = (self.time, self.step, self.h_prev);
            self.links[w]
                .set_clock(t, s, h)
                .map_err(|e| self.worker_error(w, e))?;
        }
        let setup = Setup {
            gravity,
            contact: self.contact,
        };
        let cmds = per_worker
            .into_iter()
            .zip(&self.layout)
            .map(|(bs, lay)| {
                vec![
                    Command::Setup(setup),
                    Command::Load(bs),
                    Command::Regroup(lay.clone()),
                ]
            })
            .collect();
        for (w, r) in self.exchange(cmds)?.into_iter().enumerate() {
            if r.iter().any(|x| !matches!(x, Reply::Ack)) {
                return Err(self.bad_reply(w, "Setup/Load/Regroup"));
            }
        }
        Ok(())
    }
}
