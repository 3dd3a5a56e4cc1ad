//! A Step, and the split groups' halo exchanged directly with the other holders
//! (protocol v18):
//! after the integration of a Step with `direct`, this worker sends each other holder
//! of its split groups its part states of the groups they share (what the master
//! would relay in a Halo) and reads theirs, then computes the Halo's second half here
//! and puts its outcome into the Step's report (`StepReport::halo`). A fault or error
//! before that sends the peers an abort instead, so no holder waits for states that
//! will not come. The transport is crash-link's `peer`.

use super::Engine;
use crate::error::EngineError;
use crash_core::partition::{PartState, SplitFigures};
use crash_core::{Clock, Due};
use crash_link::peer::Peers;
use crash_link::wire::{peer_halo_from_pb, peer_halo_to_pb};
use crash_link::{Halo, Reply, StepReport};
use crash_proto::pb;
use std::collections::BTreeMap;

impl Engine {
    /// A Step: the whole groups, then the split groups (their pending contact pass and
    /// integration); with `direct`, the halo with the other holders (or, after a fault
    /// or an error, their stop).
    pub(super) fn step(
        &mut self,
        at: &Clock,
        dt: f64,
        kin_nodes: bool,
        due: Due,
        contact: &SplitFigures,
        direct: bool,
    ) -> Reply {
        let reply = if let Err(e) = self.check_clock(at) {
            Reply::Error(e.to_string())
        } else if !(dt.is_finite() && dt > 0.0) {
            Reply::Error(EngineError::Step { step: at.step, dt }.to_string())
        } else {
            let mut reply = self.run(|g| g.advance_with(at, dt, due), kin_nodes);
            match &mut reply {
                Reply::Report(rep) => {
                    if let Some(fault) = self.step_shared(at, dt, due, contact, rep) {
                        reply = fault;
                    } else {
                        if direct {
                            self.direct_halo(at, dt, rep);
                        }
                        self.at = Some(at.after(dt));
                        return reply;
                    }
                }
                // a whole group faulted: the split groups' pending passes still give
                // the step before its contact rows
                Reply::Fault { split_contacts, .. } => {
                    *split_contacts = self.share_after_fault(0, contact, Vec::new());
                    self.at = Some(at.after(dt));
                }
                _ => self.at = Some(at.after(dt)),
            }
            reply
        };
        // the other holders wait for this worker's part states: tell them
        if direct {
            self.abort_peers(at);
        }
        reply
    }

    /// Take part in the direct halo exchange from now on (a worker process).
    pub fn with_peers(mut self, peers: Peers) -> Self {
        self.peers = Some(peers);
        self
    }

    /// The frame for each other holder of the split groups held here: its address and
    /// the part states `parts` of the groups it shares (None: an abort).
    fn peer_frames(
        &self,
        step: u64,
        parts: Option<Vec<PartState>>,
    ) -> Result<Vec<(u32, String, pb::PeerHalo)>, String> {
        let mut to: BTreeMap<u32, (String, Vec<PartState>)> = BTreeMap::new();
        for s in &self.shared {
            for (slot, (&w, addr)) in s.workers.iter().zip(&s.peers).enumerate() {
                if slot as u32 == s.slot {
                    continue;
                }
                if addr.is_empty() {
                    return Err(format!("worker {w} takes no direct halo connections"));
                }
                to.entry(w).or_insert_with(|| (addr.clone(), Vec::new()));
            }
        }
        let abort = parts.is_none();
        for p in parts.into_iter().flatten() {
            let Some(s) = self.shared.iter().find(|s| s.ids().contains(&p.id)) else {
                continue;
            };
            for (slot, w) in s.workers.iter().enumerate() {
                if slot as u32 != s.slot {
                    if let Some(t) = to.get_mut(w) {
                        t.1.push(p.clone());
                    }
                }
            }
        }
        Ok(to
            .into_iter()
            .map(|(w, (addr, ps))| (w, addr, peer_halo_to_pb(step, (!abort).then_some(&ps[..]))))
            .collect())
    }

    /// Exchange the part states of `rep` with the other holders and run the halo:
    /// its outcome into `rep.halo` (None when a holder aborted: its fault is the
    /// step's outcome).
    pub(super) fn direct_halo(&mut self, at: &Clock, dt: f64, rep: &mut StepReport) {
        if self.shared.is_empty() {
            return;
        }
        let parts = std::mem::take(&mut rep.parts);
        let received = match self.send_to_peers(at.step, Some(parts)) {
            Ok(()) => {
                // while the states travel: the elements that read no halo node
                for s in &mut self.shared {
                    let t = std::time::Instant::now();
                    s.inner_forces(at, dt);
                    s.nanos += t.elapsed().as_nanos() as u64;
                }
                self.receive_from_peers(at.step)
            }
            Err(e) => Err(e),
        };
        let received = match received {
            Ok(r) => r,
            Err(e) => {
                tracing::warn!(
                    "step {}: the direct halo exchange with the other holders failed: {e}",
                    at.step
                );
                rep.halo = Some(Box::new(Halo::Lost(e)));
                return;
            }
        };
        let Some(parts) = received else {
            return;
        };
        rep.halo = Some(Box::new(Halo::from_reply(self.halo(parts))));
    }

    /// Tell the other holders that this worker stopped (a fault or an error in a Step
    /// with `direct`), reading what they sent meanwhile so no frame is left behind.
    pub(super) fn abort_peers(&mut self, at: &Clock) {
        if self.shared.is_empty() {
            return;
        }
        if let Err(e) = self.exchange_with_peers(at.step, None) {
            tracing::warn!(
                "step {}: telling the other holders of the stop: {e}",
                at.step
            );
        }
    }

    /// Send `parts` (None: an abort) and read every peer's frame of step `step`: their
    /// part states in worker order, or None if one of them aborted.
    fn exchange_with_peers(
        &mut self,
        step: u64,
        parts: Option<Vec<PartState>>,
    ) -> Result<Option<Vec<PartState>>, String> {
        self.send_to_peers(step, parts)?;
        self.receive_from_peers(step)
    }

    fn peers(&mut self) -> Result<&mut Peers, String> {
        self.peers
            .as_mut()
            .ok_or_else(|| "this worker takes no direct halo connections".to_string())
    }

    /// Start the exchange: `parts` (None: an abort) on their way to the peers.
    fn send_to_peers(&mut self, step: u64, parts: Option<Vec<PartState>>) -> Result<(), String> {
        let out = self.peer_frames(step, parts)?;
        self.peers()?.send(out).map_err(|e| e.to_string())
    }

    /// Finish the exchange: every peer's frame of step `step`, their part states in
    /// worker order, or None if one of them aborted.
    fn receive_from_peers(&mut self, step: u64) -> Result<Option<Vec<PartState>>, String> {
        let peers = self.peers()?;
        let frames = peers.receive().map_err(|e| e.to_string())?;
        let mut all = Vec::new();
        let mut aborted = false;
        for (w, f) in frames {
            match peer_halo_from_pb(&f) {
                Ok((s, _)) if s != step => {
                    peers.close_all();
                    return Err(format!(
                        "worker {w} sent the halo of step {s} in step {step}"
                    ));
                }
                Ok((_, Some(p))) => all.extend(p),
                Ok((_, None)) => aborted = true,
                Err(e) => {
                    peers.close_all();
                    return Err(format!("worker {w} sent a halo that does not decode: {e}"));
                }
            }
        }
        Ok((!aborted).then_some(all))
    }
}
