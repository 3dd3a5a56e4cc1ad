//! The master: one loop for every mode, split by job.
//!
//! - `time_loop`: start, one global step, the end (dt rule, energy ledger, guards);
//! - `barrier`: commands out to every worker, replies back in body-id order;
//! - `placement`: MEIM update, groups onto workers, migration of bodies;
//! - `output`: frames gathered from the workers when one is due;
//! - `resume`: the loop's state into a checkpoint and back;
//! - `plausible`: what workers send checked against what can be true;
//! - `recover`: a lost worker dropped, the run rolled back to the last checkpoint on
//!   the survivors;
//! - `newcomers`: workers that join after the start, added at step boundaries;
//! - `confirm`: a worker's fault replayed elsewhere to tell a real one from a lie;
//! - `split`: groups larger than their share split over workers (relay, assembly).
//!
//! The master keeps one small record per body (`BodyInfo`) and the reports of the last
//! step; it holds no nodal data between output times.

use crate::error::MasterError;
use crate::input::{BodySource, ResultRequest, RunInput, RunOptions};
use crate::join::Newcomers;
use crate::meim::Meim;
use crate::pairs::PairSearch;
use crate::stats::RunStats;
use crash_core::contact::{ContactConfig, PairStats};
use crash_core::{
    BodyBrief, BodyReport, Clock, EnergyLedger, KinematicWork, NodeProbe, RunConfig, Vec3,
};
use crash_link::{LinkError, WorkerLink};

mod barrier;
mod confirm;
mod groups;
mod halo;
mod held;
mod newcomers;
mod output;
mod part_frames;
mod placement;
mod plausible;
mod recover;
mod results;
mod resume;
mod split;
mod time_loop;

/// What the master keeps per body (index = position in the sorted id list).
#[derive(Debug, Clone, Copy)]
struct BodyInfo {
    id: u32,
    thickness: f64,
    /// In the MEIM (contact on for the scene and the body).
    meshes: bool,
    /// Extra inflation of the MEIM box over the contact search box.
    extra: f64,
    /// Largest move per step the margin argument allows.
    allowed: f64,
    estimate: f64,
    nodes: usize,
    elements: usize,
    /// Every DOF prescribed: never joins a group, lends read-only copies.
    kinematic: bool,
}

/// One group as a worker holds it: its members and its read-only copies (ids, sorted).
pub(crate) type GroupLayout = (Vec<u32>, Vec<u32>);

/// Relative tolerance of the end-time and output-time comparisons (as the driver).
const TIME_EPS: f64 = 1e-12;

/// A worker of the run: one the caller gave (borrowed) or one that joined later (owned
/// by the master; dropped with it).
enum Slot<'a, L> {
    Given(&'a mut L),
    Joined(L),
}

impl<L> std::ops::Deref for Slot<'_, L> {
    type Target = L;
    fn deref(&self) -> &L {
        match self {
            Slot::Given(l) => l,
            Slot::Joined(l) => l,
        }
    }
}

impl<L> std::ops::DerefMut for Slot<'_, L> {
    fn deref_mut(&mut self) -> &mut L {
        match self {
            Slot::Given(l) => l,
            Slot::Joined(l) => l,
        }
    }
}

pub(crate) struct Master<'a, L: WorkerLink> {
    links: Vec<Slot<'a, L>>,
    /// Where workers that attach after the start come from (None: nowhere).
    joiner: Option<&'a mut (dyn Newcomers<L> + 'a)>,
    /// Newcomers that hold no body yet (the log says when they first get some).
    fresh: Vec<usize>,
    /// A newcomer joined: place the groups anew at this step's regroup.
    rebalance: bool,
    /// The worker and fault of the last exchange's fault reply (`confirm`).
    faulted: Option<(usize, crash_core::Fault)>,
    /// Each worker's share of the pending split contact pass from the exchange that
    /// faulted (None where none came back), for the rows held (`held`).
    fault_shares: Option<Vec<Option<Vec<crash_core::contact::PairStats>>>>,
    /// A fault being replayed on the other workers (`confirm`).
    suspect: Option<confirm::Suspect>,
    /// Workers still in the run (a lost one is dropped for good; indices stay; a
    /// suspect is out while its fault is replayed).
    live: Vec<bool>,
    /// Workers found gone or frozen by the last exchange, not yet dropped.
    lost: Vec<(usize, LinkError)>,
    /// Where definitions come from when a survivor needs one it never received.
    source: Option<BodySource>,
    /// Verlet skin of the level-i search (a rollback starts the list afresh).
    skin: f64,
    /// Workers dropped so far (each followed by a rollback).
    recoveries: u64,
    /// A direct halo exchange between workers failed: split steps relay through the
    /// master for the rest of the run (`split.rs`).
    direct_failed: bool,
    opts: RunOptions,
    cfg: RunConfig,
    contact: ContactConfig,
    gravity: Vec3,
    output_interval: f64,
    info: Vec<BodyInfo>,
    cost: Vec<f64>,
    measured: Vec<Option<f64>>,
    worker_of: Vec<Option<usize>>,
    layout: Vec<Vec<GroupLayout>>,
    meim: Meim,
    /// Contact work on the kinematic bodies so far (summed in pair order).
    kinematic: KinematicWork,
    /// Body names (index = position in the sorted id list), for messages.
    names: Vec<String>,
    /// Compute time of each group in the last step [ns], at the index of its smallest
    /// id (0: no group starts there). A vector, not a map: filled for every group of
    /// every step.
    group_ns: Vec<u64>,
    /// Compute time of each holder's parts of a split group in the last step: (worker,
    /// the split's first id, ns). Every holder reports under the same first id.
    split_ns: Vec<(usize, u32, u64)>,
    /// Splits planned at the start, made after the first rollback point
    /// (`split::plan_at_start`).
    planned: Vec<split::SplitGroup>,
    /// The master's merge of the split groups' shares in this step's exchange [ns]
    /// (a part of the barrier: `BarrierStats::master_merge_ns`).
    merge_ns: u64,
    /// Step of the last group rows handed to the sink.
    groups_step: Option<u64>,
    search: PairSearch,
    scene_hash: u64,
    /// The run's one clock.
    clock: Clock,
    next_dt: f64,
    dt0: f64,
    ledger: EnergyLedger,
    reports: Vec<BodyReport>,
    /// Which reports the current gather has filled (kept to avoid allocating per step).
    seen: Vec<bool>,
    contacts: Vec<PairStats>,
    /// `contacts` carry the per-node forces on kinematic bodies (the step asked).
    kin_nodes: bool,
    /// The result files' requests, and the history nodes of the last step (with their
    /// mesh-file node ids, sorted by body and node).
    results: ResultRequest,
    probed: Vec<(u64, NodeProbe)>,
    frames: u64,
    last_frame_step: Option<u64>,
    /// The step whose frame gave `stats.final_hash` (frames before the end are not
    /// hashed: `output`).
    hashed_step: Option<u64>,
    /// Groups split over workers (`split`).
    splits: Vec<split::SplitGroup>,
    /// The frame of each body split so far as it was when split: what its frames take
    /// from the definition (initial positions, connectivity), the rest overwritten by
    /// its parts' shares (`part_frames`).
    skeletons: std::collections::BTreeMap<u32, crash_io::FrameBody>,
    /// Every split body's element step over all its parts in the last step and every
    /// pair's closing-speed figures, for the contact pass it left pending (empty when
    /// none is): the next Step carries them.
    split_contact: crash_core::partition::SplitFigures,
    /// The last step's contact rows while its split groups' contact pass is pending.
    held: Option<held::HeldRows>,
    /// The split groups' contact statistics of a pass run in the step (the segment
    /// pass: `contact_in_step`), merged over the holders, for this step's rows.
    split_now: Option<Vec<crash_core::contact::PairStats>>,
    pub(crate) stats: RunStats,
}

impl<'a, L: WorkerLink> Master<'a, L> {
    pub(crate) fn new(
        links: &'a mut [L],
        joiner: Option<&'a mut (dyn Newcomers<L> + 'a)>,
        input: &RunInput,
        opts: RunOptions,
    ) -> Result<Self, MasterError> {
        if links.is_empty() {
            return Err(MasterError::Input("a run needs at least one worker".into()));
        }
        if input.briefs.is_empty() {
            return Err(MasterError::Input("the scene has no bodies".into()));
        }
        if !(opts.margin_factor >= 1.0 && opts.margin_factor.is_finite()) {
            return Err(MasterError::Input(format!(
                "margin factor {} must be finite and >= 1",
                opts.margin_factor
            )));
        }
        let mut sorted: Vec<&BodyBrief> = input.briefs.iter().collect();
        sorted.sort_by_key(|b| b.id);
        let ids: Vec<u32> = sorted.iter().map(|b| b.id).collect();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(MasterError::Input(format!(
                "two bodies have the id {}",
                w[0]
            )));
        }
        let c = input.contact;
        let info: Vec<BodyInfo> = sorted
            .iter()
            .map(|b| {
                let m = c.margin_of(b.thickness);
                let meshes = c.enabled && b.contact;
                BodyInfo {
                    id: b.id,
                    thickness: b.thickness,
                    meshes,
                    extra: 0.5 * (opts.margin_factor - 1.0) * m,
                    allowed: 0.5 * (opts.margin_factor - 1.0) * m,
                    estimate: 1.0
                        + if b.kinematic { 0.0 } else { b.elements as f64 }
                        + if meshes { b.nodes as f64 } else { 0.0 },
                    nodes: b.nodes,
                    elements: b.elements,
                    kinematic: b.kinematic,
                }
            })
            .collect();
        let n = info.len();
        let kinematic: Vec<u32> = info.iter().filter(|i| i.kinematic).map(|i| i.id).collect();
        // Verlet skin of the level-i search: the MEIM margin of the widest body
        let skin = sorted
            .iter()
            .filter(|b| c.enabled && b.contact)
            .map(|b| opts.margin_factor * c.margin_of(b.thickness))
            .fold(0.0, f64::max);
        Ok(Self {
            live: vec![true; links.len()],
            links: links.iter_mut().map(Slot::Given).collect(),
            joiner,
            fresh: Vec::new(),
            rebalance: false,
            faulted: None,
            fault_shares: None,
            suspect: None,
            lost: Vec::new(),
            source: None,
            skin,
            recoveries: 0,
            direct_failed: false,
            opts,
            cfg: input.config,
            contact: c,
            gravity: input.gravity,
            output_interval: input.output_interval,
            cost: info.iter().map(|i| i.estimate).collect(),
            measured: vec![None; n],
            worker_of: vec![None; n],
            layout: Vec::new(),
            meim: Meim::new(&ids, opts.split_after).with_kinematic(&kinematic),
            kinematic: KinematicWork::new(
                sorted
                    .iter()
                    .filter(|b| b.kinematic)
                    .map(|b| (b.id, b.programs.clone(), b.curves.clone())),
            ),
            names: input.names_by_id(&ids),
            group_ns: Default::default(),
            split_ns: Vec::new(),
            merge_ns: 0,
            planned: Vec::new(),
            groups_step: None,
            search: PairSearch::new(c.margin, skin),
            info,
            scene_hash: input.scene_hash,
            clock: Clock::default(),
            next_dt: 0.0,
            dt0: 0.0,
            ledger: EnergyLedger::default(),
            reports: Vec::with_capacity(n),
            seen: Vec::with_capacity(n),
            contacts: Vec::new(),
            kin_nodes: false,
            results: input.results.clone(),
            probed: Vec::new(),
            frames: 0,
            last_frame_step: None,
            hashed_step: None,
            splits: Vec::new(),
            skeletons: Default::default(),
            split_contact: Default::default(),
            held: None,
            split_now: None,
            stats: RunStats::default(),
        })
    }

    fn index(&self, id: u32) -> Option<usize> {
        let i = id as usize;
        if self.info.get(i).is_some_and(|b| b.id == id) {
            return Some(i);
        }
        self.info.binary_search_by_key(&id, |b| b.id).ok()
    }

    fn is_kinematic(&self, id: u32) -> bool {
        self.index(id).is_some_and(|i| self.info[i].kinematic)
    }

    fn kinematic_ids(&self) -> Vec<u32> {
        self.info
            .iter()
            .filter(|i| i.kinematic)
            .map(|i| i.id)
            .collect()
    }

    /// A body's name for messages (escaped where it came from a peer: names come from
    /// the scene the master read itself).
    fn name(&self, id: u32) -> &str {
        self.index(id).map_or("?", |i| self.names[i].as_str())
    }

    /// Worker `w` (given or joined).
    pub(crate) fn link(&self, w: usize) -> Option<&L> {
        self.links.get(w).map(|l| &**l)
    }

    pub(crate) fn max_energy_error(&self) -> f64 {
        self.ledger.max_error()
    }

    /// Best-effort shutdown of every worker still in the run (some may be gone).
    pub(crate) fn shutdown(&mut self, reason: &str) {
        // a worker whose fault is being replayed is still in the run
        if let Some(s) = self.suspect.take() {
            self.live[s.worker] = true;
        }
        for (l, &live) in self.links.iter_mut().zip(&self.live) {
            if live {
                l.close(reason);
            }
        }
    }

    /// Workers dropped so far.
    pub(crate) fn recoveries(&self) -> u64 {
        self.recoveries
    }

    /// Workers still in the run.
    pub(crate) fn live_count(&self) -> usize {
        self.live.iter().filter(|&&l| l).count()
    }
}

fn ns(t: std::time::Instant) -> u64 {
    t.elapsed().as_nanos() as u64
}
