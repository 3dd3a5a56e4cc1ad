//! Groups split over workers (issue 16 point 2): the worker side of `Split`, `Share`,
//! the split groups' part of a `Step` (the previous step's pending contact pass with
//! the element steps the Step carries, then the integration), the step's second
//! exchange (`Halo`), the contact pass before an assembly (`Contact`), and the
//! assembly of whole bodies (`Parts`, `Assemble`, `Unsplit`). The physics is `crash_core::partition::
//! SharedGroup`; here are the bookkeeping and the checks.
//!
//! The worker that held the group when it was split (its *home*) keeps answering for
//! its bodies: frames, states and merging back read the whole bodies it assembles from
//! every holder's parts (`Assemble`, at the clock they are asked at). The other holders
//! hold parts only: their bodies are not theirs (never listed by a Regroup, never in
//! their frames or states).

use super::Engine;
use crate::error::EngineError;
use crash_core::contact::PairStats;
use crash_core::partition::{PartState, SharedGroup, SplitFigures};
use crash_core::{Body, BodyState, Clock, Due};
use crash_io::PartFrame;
use crash_link::{BodyLoad, Reply, SplitSpec, StepReport};
use std::time::Instant;

/// A group split here whose parts are not built yet (`Engine::settle`).
#[derive(Debug)]
pub(crate) struct Unbuilt {
    bodies: Vec<Body>,
    parts: Vec<usize>,
    mine: Vec<Vec<bool>>,
    spec: SplitSpec,
}

/// One split group this worker holds parts of.
#[derive(Debug)]
pub(crate) struct Shared {
    g: SharedGroup,
    /// This worker split the group (it answers for its bodies).
    home: bool,
    /// The whole bodies as last assembled (home only), and the clock of the assembly.
    whole: Vec<Body>,
    assembled: Option<Clock>,
    /// Compute time of the step in flight [ns].
    pub(super) nanos: u64,
    /// This worker's slot, the worker of each slot and where it takes direct halo
    /// connections (the split's spec).
    pub(super) slot: u32,
    pub(super) workers: Vec<u32>,
    pub(super) peers: Vec<String>,
}

impl Shared {
    fn new(
        g: SharedGroup,
        home: bool,
        whole: Vec<Body>,
        assembled: Option<Clock>,
        spec: SplitSpec,
    ) -> Self {
        Self {
            g,
            home,
            whole,
            assembled,
            nanos: 0,
            slot: spec.slot,
            workers: spec.workers,
            peers: spec.peers,
        }
    }

    pub(super) fn ids(&self) -> &[u32] {
        &self.g.ids
    }

    /// The element chunks of this holder's parts that read no halo node (while the
    /// other holders' states travel).
    pub(super) fn inner_forces(&mut self, at: &Clock, dt: f64) -> usize {
        self.g.inner_forces(at, dt)
    }

    fn first(&self) -> u32 {
        self.g.ids.first().copied().unwrap_or(0)
    }
}

/// The element steps of the bodies of `g`, in its order, and the closing-speed
/// figures of its pairs, from the master's lists.
fn dts_of(g: &SharedGroup, all: &SplitFigures) -> Result<SplitFigures, EngineError> {
    let dts = g
        .ids
        .iter()
        .map(|id| {
            all.dts
                .iter()
                .find(|d| d.id == *id)
                .copied()
                .ok_or_else(|| {
                    EngineError::Shared(format!(
                        "no element step of split body {id} for its pending contact pass"
                    ))
                })
        })
        .collect::<Result<_, _>>()?;
    let pairs = all
        .pairs
        .iter()
        .filter(|p| g.ids.contains(&p.a) && g.ids.contains(&p.b))
        .copied()
        .collect();
    Ok(SplitFigures { dts, pairs })
}

fn mine(spec: &SplitSpec) -> Result<(Vec<usize>, Vec<Vec<bool>>), EngineError> {
    let bad = |what: &str| EngineError::Shared(what.to_string());
    if spec.parts.len() != spec.ids.len() || spec.holder.len() != spec.ids.len() {
        return Err(bad("the split's columns differ in length"));
    }
    let parts: Vec<usize> = spec.parts.iter().map(|&k| k as usize).collect();
    let mut mine = Vec::with_capacity(parts.len());
    for (k, h) in parts.iter().zip(&spec.holder) {
        if *k == 0 || h.len() != *k {
            return Err(bad("a body without parts, or holders not one per part"));
        }
        mine.push(h.iter().map(|&w| w == spec.slot).collect());
    }
    Ok((parts, mine))
}

impl Engine {
    pub(super) fn split_home_ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.shared
            .iter()
            .filter(|s| s.home)
            .flat_map(|s| s.g.ids.iter().copied())
    }

    pub(super) fn split_home_bodies(&self) -> impl Iterator<Item = &Body> + '_ {
        self.shared
            .iter()
            .filter(|s| s.home)
            .flat_map(|s| s.whole.iter())
    }

    /// Whole bodies of the split groups are current (frames and states read them).
    pub(super) fn check_assembled(&self) -> Result<(), EngineError> {
        self.check_assembled_of(None)
    }

    /// `check_assembled` for the split groups holding one of `ids` (None: all). Whole
    /// bodies' frames do not wait for an assembly of split groups whose frames come
    /// from their parts.
    pub(super) fn check_assembled_of(&self, ids: Option<&[u32]>) -> Result<(), EngineError> {
        let asked = |s: &&Shared| ids.is_none_or(|ids| s.g.ids.iter().any(|id| ids.contains(id)));
        for s in self.shared.iter().filter(|s| s.home).filter(asked) {
            let now = match (s.assembled, self.at) {
                (Some(a), Some(b)) => a.same_as(&b),
                _ => false,
            };
            if !now {
                return Err(EngineError::Shared(format!(
                    "the group of body {} was not assembled at this clock",
                    s.first()
                )));
            }
        }
        Ok(())
    }

    fn setup_of(&self) -> Result<&crash_link::Setup, EngineError> {
        self.setup.as_ref().ok_or(EngineError::NoSetup)
    }

    /// Split one of this worker's groups; its whole bodies for the other holders. Its
    /// own parts are built after the reply (`settle`): while the master relays the
    /// bodies and the other holders build theirs.
    pub(super) fn split(&mut self, spec: SplitSpec) -> Result<Reply, EngineError> {
        let (parts, mine) = mine(&spec)?;
        let at = self.group_of_split(&spec)?;
        self.setup_of()?;
        let bodies = self.groups.remove(at).bodies;
        let out = bodies.iter().cloned().map(BodyLoad::whole).collect();
        self.unbuilt = Some(Unbuilt {
            bodies,
            parts,
            mine,
            spec,
        });
        Ok(Reply::Unloaded(out))
    }

    /// Build the parts of a group split here whose reply has gone (a worker calls it
    /// once the reply is on its way; every command calls it first). A build that
    /// fails leaves the engine broken: the next command is refused with the reason.
    pub fn settle(&mut self) {
        let Some(u) = self.unbuilt.take() else {
            return;
        };
        let built = self.setup_of().and_then(|s| {
            Ok(
                SharedGroup::new(&u.bodies, &u.parts, u.mine, s.contact, s.gravity)?
                    .with_holders(u.spec.holder.clone()),
            )
        });
        match built {
            Ok(g) => self
                .shared
                .push(Shared::new(g, true, u.bodies, self.at, u.spec)),
            Err(e) => {
                self.broken = true;
                self.unbuildable = Some(e.to_string());
            }
        }
    }

    /// Hold parts of a group another worker split; without bodies, of the group held
    /// here (a split planned at the start: every holder was loaded with the group and
    /// started it; slot 0, the home, keeps answering for its bodies).
    pub(super) fn share(
        &mut self,
        at: Clock,
        spec: SplitSpec,
        bodies: Vec<BodyLoad>,
    ) -> Result<Reply, EngineError> {
        self.check_clock(&at)?;
        if bodies.is_empty() {
            return self.share_held(spec);
        }
        let (parts, mine) = mine(&spec)?;
        if !bodies.iter().map(|b| b.id).eq(spec.ids.iter().copied()) {
            return Err(EngineError::Shared(
                "the bodies sent are not the split's".into(),
            ));
        }
        let mut whole = Vec::with_capacity(bodies.len());
        for b in bodies {
            let known = self.defs.get(&b.id).cloned();
            let body = b.into_body(known.as_ref())?;
            self.defs.insert(body.def.id, body.def.clone());
            whole.push(body);
        }
        let setup = self.setup_of()?;
        let g = SharedGroup::new(&whole, &parts, mine, setup.contact, setup.gravity)?
            .with_holders(spec.holder.clone());
        self.shared
            .push(Shared::new(g, false, Vec::new(), None, spec));
        self.at = Some(at);
        Ok(Reply::Ack)
    }

    fn share_held(&mut self, spec: SplitSpec) -> Result<Reply, EngineError> {
        let (parts, mine) = mine(&spec)?;
        let at = self.group_of_split(&spec)?;
        let setup = self.setup_of()?;
        let (contact, gravity) = (setup.contact, setup.gravity);
        let g = SharedGroup::new(&self.groups[at].bodies, &parts, mine, contact, gravity)?
            .with_holders(spec.holder.clone());
        let bodies = self.groups.remove(at).bodies;
        let home = spec.slot == 0;
        let (whole, assembled) = if home {
            (bodies, self.at)
        } else {
            (Vec::new(), None)
        };
        self.shared
            .push(Shared::new(g, home, whole, assembled, spec));
        Ok(Reply::Ack)
    }

    /// Where the whole group `spec` splits is among the groups (without copies).
    fn group_of_split(&self, spec: &SplitSpec) -> Result<usize, EngineError> {
        self.groups
            .iter()
            .position(|g| {
                g.copies.is_empty() && g.owned().map(|b| b.def.id).eq(spec.ids.iter().copied())
            })
            .ok_or_else(|| {
                EngineError::Shared(format!("no group {:?} (without copies) here", spec.ids))
            })
    }

    /// Phase 1 of a step for the split groups (after the whole groups): the pending
    /// contact pass of the previous step with the element steps `contact` (every split
    /// body's, merged by the master), then the integration; the states of the parts
    /// computed here into the report. Some: the reply of a failure.
    pub(super) fn step_shared(
        &mut self,
        at: &Clock,
        dt: f64,
        due: Due,
        contact: &SplitFigures,
        rep: &mut StepReport,
    ) -> Option<Reply> {
        self.pending = Some((*at, dt, due));
        for k in 0..self.shared.len() {
            let s = &mut self.shared[k];
            let t = Instant::now();
            if s.g.contact_pending() {
                let builds = s.g.split.builds;
                let r = match dts_of(&s.g, contact) {
                    Ok(d) => s.g.contact(&d),
                    Err(e) => return Some(Reply::Error(e.to_string())),
                };
                if let Err(e) = r {
                    let first = s.first();
                    return Some(self.failed(first, e));
                }
                rep.split_contacts
                    .extend_from_slice(s.g.split.contact_stats());
                if s.g.split.builds != builds {
                    tracing::debug!(
                        "step {}: split group of body {}: contact views built ({} so far), export nodes per part {:?}",
                        at.step,
                        s.first(),
                        s.g.split.builds,
                        s.g.export.iter().map(|e| e.iter().map(Vec::len).collect::<Vec<_>>()).collect::<Vec<_>>()
                    );
                }
            }
            let r: Result<Vec<PartState>, _> = s.g.integrate(at, dt);
            s.nanos = t.elapsed().as_nanos() as u64;
            match r {
                Ok(p) => rep.parts.extend(p),
                Err(fault) => {
                    let group_first = s.first();
                    self.broken = true;
                    let ran = std::mem::take(&mut rep.split_contacts);
                    return Some(Reply::Fault {
                        group_first,
                        fault,
                        split_contacts: self.share_after_fault(k + 1, contact, ran),
                    });
                }
            }
        }
        None
    }

    /// This worker's share of the pending contact passes after a fault in a Step:
    /// `ran`, the shares of the split groups before `from`, then the passes of the
    /// groups from `from` on run now (each reads only its own group's states, which
    /// the fault did not touch). None when one of them fails: the step's rows are then
    /// not complete.
    pub(super) fn share_after_fault(
        &mut self,
        from: usize,
        contact: &SplitFigures,
        mut ran: Vec<PairStats>,
    ) -> Option<Vec<PairStats>> {
        for s in self.shared.iter_mut().skip(from) {
            if !s.g.contact_pending() {
                continue;
            }
            let d = dts_of(&s.g, contact).ok()?;
            s.g.contact(&d).ok()?;
            ran.extend_from_slice(s.g.split.contact_stats());
        }
        Some(ran)
    }

    /// The reply to a split group's failure: a fault of the run (the engine is broken
    /// until the master rolls back), or an error of the command.
    fn failed(&mut self, group_first: u32, e: crash_core::partition::SplitError) -> Reply {
        match e {
            crash_core::partition::SplitError::Fault(fault) => {
                self.broken = true;
                // the pass that faulted leaves the step's rows incomplete
                Reply::Fault {
                    group_first,
                    fault,
                    split_contacts: None,
                }
            }
            e => Reply::Error(EngineError::Shared(e.to_string()).to_string()),
        }
    }

    fn in_flight(&self, what: &'static str) -> Result<(Clock, f64, Due), EngineError> {
        if self.broken {
            return Err(EngineError::Broken);
        }
        self.pending
            .ok_or_else(|| EngineError::Shared(format!("{what} without a step")))
    }

    /// Phase 2: the other holders' part states; element forces here, and this
    /// worker's share of the split bodies' reports with their element steps over the
    /// parts here (`StepReport::part_dts`). The contact pass stays pending.
    pub(super) fn halo(&mut self, parts: Vec<PartState>) -> Reply {
        let (at, dt, due) = match self.in_flight("Halo") {
            Ok(p) => p,
            Err(e) => return Reply::Error(e.to_string()),
        };
        self.pending = None;
        let reactions = self.setup.as_ref().is_some_and(|s| s.reactions) && due.reactions;
        let mut rep = StepReport::default();
        for s in &mut self.shared {
            let t = Instant::now();
            let mine: Vec<PartState> = parts
                .iter()
                .filter(|p| s.g.ids.contains(&p.id))
                .cloned()
                .collect();
            match s.g.forces(&mine, &at, dt, reactions) {
                Ok((shares, d)) => {
                    rep.bodies.extend(shares);
                    rep.part_dts.dts.extend(d.dts);
                    rep.part_dts.pairs.extend(d.pairs);
                }
                Err(e) => {
                    let first = s.first();
                    return self.failed(first, e);
                }
            }
            s.nanos += t.elapsed().as_nanos() as u64;
            rep.groups.push(crash_link::GroupTime {
                first: s.first(),
                nanos: s.nanos,
            });
        }
        // the split groups' compute over the step (contact of the last step and
        // integration in the Step, element forces here): the master adds it to the
        // Step's, so the barrier is the rest
        rep.compute_ns = self.shared.iter().map(|s| s.nanos).sum();
        Reply::Report(rep)
    }

    /// The pending contact pass of every split group held here, before an assembly
    /// (the master sends the element steps the next Step would carry), or in the step
    /// under the segment pass; the report carries this worker's share of their contact
    /// statistics and the step limits the passes set here (`StepReport::split_limits`).
    pub(super) fn contact(&mut self, dts: SplitFigures) -> Reply {
        if self.broken {
            return Reply::Error(EngineError::Broken.to_string());
        }
        let mut rep = StepReport::default();
        let t0 = Instant::now();
        for k in 0..self.shared.len() {
            let s = &mut self.shared[k];
            if !s.g.contact_pending() {
                continue;
            }
            let t = Instant::now();
            let r = match dts_of(&s.g, &dts) {
                Ok(d) => s.g.contact(&d),
                Err(e) => return Reply::Error(e.to_string()),
            };
            s.nanos += t.elapsed().as_nanos() as u64;
            match r {
                Ok(limits) => rep.split_limits.extend(limits),
                Err(e) => {
                    let first = s.first();
                    return self.failed(first, e);
                }
            }
            rep.split_contacts
                .extend_from_slice(s.g.split.contact_stats());
        }
        rep.compute_ns = t0.elapsed().as_nanos() as u64;
        Reply::Report(rep)
    }

    /// No contact pass is pending (an assembly reads the contact forces).
    fn check_no_contact_pending(&self) -> Result<(), EngineError> {
        match self.shared.iter().find(|s| s.g.contact_pending()) {
            Some(s) => Err(EngineError::Shared(format!(
                "the contact pass of the group of body {} is pending: Contact first",
                s.first()
            ))),
            None => Ok(()),
        }
    }

    /// The parts computed here of the groups other workers split.
    pub(super) fn parts(&self) -> Reply {
        if let Err(e) = self.check_no_contact_pending() {
            return Reply::Error(e.to_string());
        }
        Reply::Parts(
            self.shared
                .iter()
                .filter(|s| !s.home)
                .flat_map(|s| s.g.own_states())
                .collect(),
        )
    }

    /// The frame shares of the split bodies `ids` from the parts computed here (body
    /// by body in each group's order, parts in order): no whole body is assembled.
    pub(super) fn part_frames(&self, ids: &[u32]) -> Result<Vec<PartFrame>, EngineError> {
        self.check_no_contact_pending()?;
        let mut out = Vec::new();
        for s in &self.shared {
            let split = &s.g.split;
            for ((&id, body), mine) in s.g.ids.iter().zip(&split.splits).zip(&split.mine) {
                if !ids.contains(&id) {
                    continue;
                }
                for (p, _) in body.parts.iter().zip(mine).filter(|(_, &m)| m) {
                    out.push(PartFrame::capture(
                        id, &p.body, p.owned, &p.node, &p.element,
                    ));
                }
            }
        }
        Ok(out)
    }

    /// The other holders' parts of the groups split here: assemble the whole bodies.
    pub(super) fn assemble(
        &mut self,
        parts: Vec<(u32, u32, BodyState)>,
    ) -> Result<Reply, EngineError> {
        self.check_no_contact_pending()?;
        let mut parts = parts;
        for s in self.shared.iter_mut().filter(|s| s.home) {
            let (these, rest): (Vec<_>, Vec<_>) =
                parts.into_iter().partition(|p| s.g.ids.contains(&p.0));
            parts = rest;
            s.whole = s.g.assemble(these)?;
            s.assembled = self.at;
        }
        if let Some(p) = parts.first() {
            return Err(EngineError::Shared(format!(
                "part {} of body {} belongs to no group split here",
                p.1, p.0
            )));
        }
        Ok(Reply::Ack)
    }

    /// Merge the split groups back: the home holds each as a group again (assembled
    /// at this clock), the other holders forget their parts.
    pub(super) fn unsplit(&mut self) -> Result<Reply, EngineError> {
        self.check_assembled()?;
        for s in std::mem::take(&mut self.shared) {
            if s.home {
                let g = self.new_group(s.whole, Vec::new())?;
                self.groups.push(g);
            }
        }
        self.groups.sort_by_key(|g| g.first());
        self.pending = None;
        Ok(Reply::Ack)
    }
}
