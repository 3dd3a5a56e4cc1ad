//! The loop's state into a checkpoint, and a run continued from one on any set of
//! workers (the clock travels with the loads and every step).

use super::output::Piece;
use super::Master;
use crate::checkpoint::MasterCheckpoint;
use crate::error::MasterError;
use crate::input::BodySource;
use crate::meim::Meim;
use crate::pairs::PairSearch;
use crash_core::Body;
use crash_link::{BodyLoad, Command, Reply, WorkerLink};

impl<L: WorkerLink> Master<'_, L> {
    /// The state after the current step (body states gathered from the workers).
    pub(crate) fn checkpoint(&mut self) -> Result<MasterCheckpoint, MasterError> {
        self.assemble_splits()?;
        let nw = self.links.len();
        // in the frame's pieces (bounded size: each reply stays under MAX_MESSAGE)
        let mut cmds: Vec<Vec<Command>> = vec![Vec::new(); nw];
        // (every body from its worker: the split groups were just assembled)
        for piece in self.frame_pieces(&Default::default()) {
            if let Piece::Worker(w, ids) = piece {
                cmds[w].push(Command::States(ids));
            }
        }
        let replies = self.exchange(cmds)?;
        let mut states = Vec::with_capacity(self.info.len());
        for (w, r) in replies.into_iter().enumerate() {
            for reply in r {
                match reply {
                    Reply::States(s) => {
                        if let Err(what) = self.check_states(w, &s) {
                            return Err(self.implausible(w, &what));
                        }
                        states.extend(s)
                    }
                    _ => return Err(self.bad_reply(w, "States")),
                }
            }
        }
        states.sort_by_key(|s| s.0);
        if !states
            .iter()
            .map(|s| s.0)
            .eq(self.info.iter().map(|i| i.id))
        {
            return Err(MasterError::Incomplete {
                step: self.clock.step,
                what: "checkpoint states",
                got: states.len(),
                expected: self.info.len(),
            });
        }
        Ok(MasterCheckpoint {
            scene_hash: self.scene_hash,
            clock: self.clock,
            next_dt: self.next_dt,
            dt0: self.dt0,
            ledger: self.ledger.clone(),
            kinematic_work: self.kinematic.clone(),
            edges: self.meim.edge_states(),
            frames: self.frames,
            last_frame_step: self.last_frame_step,
            stats: self.stats.clone(),
            states,
        })
    }

    /// The loop's state as the checkpoint holds it (clock, dt, ledger, MEIM, frame
    /// schedule, statistics); the Verlet list starts empty (the first update does a
    /// full search, whose result equals the list's).
    pub(super) fn restore_loop(&mut self, ck: &MasterCheckpoint) {
        let ids: Vec<u32> = self.info.iter().map(|i| i.id).collect();
        self.clock = ck.clock;
        self.next_dt = ck.next_dt;
        self.dt0 = ck.dt0;
        self.ledger = ck.ledger.clone();
        self.kinematic = ck.kinematic_work.clone();
        self.meim = Meim::restore(&ids, self.opts.split_after, &ck.edges)
            .with_kinematic(&self.kinematic_ids());
        self.search = PairSearch::new(self.contact.margin, self.skin);
        self.frames = ck.frames;
        self.last_frame_step = ck.last_frame_step;
        self.stats = ck.stats.clone();
    }

    /// Continue from a checkpoint instead of `start`: restore the loop's state, place
    /// the restored groups and load each body (the scene's definition with the
    /// checkpoint's state) onto its worker at the checkpoint's clock. Nothing is written
    /// to the sink (its files already hold the rows and frames up to the checkpoint).
    pub(crate) fn resume(
        &mut self,
        ck: MasterCheckpoint,
        bodies: BodySource,
    ) -> Result<(), MasterError> {
        ck.check_continues(self.scene_hash, self.cfg.end_time)?;
        let ids: Vec<u32> = self.info.iter().map(|i| i.id).collect();
        let ck_ids: Vec<u32> = ck.states.iter().map(|s| s.0).collect();
        if ck_ids != ids {
            return Err(MasterError::Input(format!(
                "the checkpoint holds bodies {ck_ids:?}, the scene {ids:?}"
            )));
        }
        let c = ck.clock;
        if !(c.time.is_finite() && ck.next_dt > 0.0 && ck.next_dt.is_finite()) {
            return Err(MasterError::Input(format!(
                "the checkpoint's clock is invalid (t = {}, next dt = {})",
                c.time, ck.next_dt
            )));
        }
        self.restore_loop(&ck);
        let placement = self.place_all();
        let mut source = Some(bodies);
        let mut states = ck.states.into_iter();
        let loaded = self.load_all(&placement, |id| {
            let body = source
                .as_mut()
                .ok_or_else(|| MasterError::Input("no bodies".into()))?
                .take(id)?;
            let (sid, state) = states.next().filter(|(sid, _)| *sid == id).ok_or_else(|| {
                MasterError::Input(format!("the checkpoint has no state of body {id}"))
            })?;
            let body = Body::from_parts(body.def, state).map_err(|e| {
                MasterError::Input(format!("the checkpoint's state of body {sid}: {e}"))
            })?;
            Ok(BodyLoad::whole(body))
        });
        self.source = source;
        loaded
    }
}
