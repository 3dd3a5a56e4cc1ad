//! The commands a master sends and the replies a worker gives (exactly one per command).

use crash_core::contact::{ContactConfig, PairStats};
use crash_core::partition::{PartState, SplitFigures};
use crash_core::{
    Body, BodyDef, BodyReport, BodyState, Clock, CoreError, Due, Fault, NodeProbe, Vec3,
};
use crash_io::{FrameBody, PartFrame};
use std::sync::Arc;

/// Run-wide parameters every group needs.
#[derive(Debug, Clone, PartialEq)]
pub struct Setup {
    pub gravity: Vec3,
    pub contact: ContactConfig,
    /// Report support reactions (spcforc.csv asked for).
    pub reactions: bool,
    /// History nodes (body id, node index), sorted (nodout.csv asked for).
    pub probes: Arc<Vec<(u32, u32)>>,
}

/// A body handed to or from a worker: its state, and its definition when the receiver
/// may lack it (`None`: the receiver already holds the definition of body `id`).
#[derive(Debug, Clone)]
pub struct BodyLoad {
    pub id: u32,
    pub def: Option<Arc<BodyDef>>,
    pub state: BodyState,
}

impl BodyLoad {
    /// A whole body (definition included), its forces in the slots (crash_core::summed).
    pub fn whole(mut b: Body) -> Self {
        b.settle();
        Self {
            id: b.def.id,
            def: Some(b.def),
            state: b.state,
        }
    }

    /// Join with a definition (the carried one, else `known`), checking that they fit.
    pub fn into_body(self, known: Option<&Arc<BodyDef>>) -> Result<Body, CoreError> {
        let def = match (self.def, known) {
            (Some(d), _) => d,
            (None, Some(d)) => d.clone(),
            (None, None) => {
                return Err(CoreError::Other {
                    body: format!("body {}", self.id),
                    what: "its state arrived without a definition, and none is held".into(),
                })
            }
        };
        if def.id != self.id {
            return Err(CoreError::Other {
                body: def.name.clone(),
                what: format!("the state of body {} came with this definition", self.id),
            });
        }
        Body::from_parts(def, self.state)
    }
}

/// What the master tells a worker. Every command gets exactly one [`Reply`].
#[derive(Debug, Clone)]
pub enum Command {
    Setup(Setup),
    /// Take these bodies; their states are at clock `at`.
    Load {
        at: Clock,
        bodies: Vec<BodyLoad>,
    },
    /// Read-only copies of kinematic bodies another worker owns, at clock `at`, for the
    /// groups of the next Regroup (a worker that holds the body or a copy of it already
    /// makes its copies itself).
    LoadCopies {
        at: Clock,
        bodies: Vec<BodyLoad>,
    },
    /// Give these bodies back and forget them; include the definition of the ids in
    /// `with_def` (their next worker lacks it).
    Unload {
        ids: Vec<u32>,
        with_def: Vec<u32>,
    },
    /// Like Unload, but keep the bodies: their state is lent to another worker's groups
    /// as read-only copies (kinematic bodies only). Answered by `Unloaded`.
    Lend {
        ids: Vec<u32>,
        with_def: Vec<u32>,
    },
    /// The groups the worker integrates from now on (each sorted by id, the groups by
    /// their smallest id); every body held appears exactly once. `copies[k]` (sorted; may
    /// be missing for the last groups): read-only copies of the kinematic bodies group k
    /// touches, each made from a body or copy the worker holds or a LoadCopies.
    Regroup {
        groups: Vec<Vec<u32>>,
        copies: Vec<Vec<u32>>,
    },
    /// Forces of the initial configuration.
    Start,
    /// Take the step of length `dt` that starts at clock `at`. `kin_nodes`: report the
    /// pass's per-node forces on kinematic bodies (`KinLoad::nodes`): a frame follows.
    /// `due`: report reactions and history nodes (when Setup turned them on): their
    /// result rows follow this step. `contact`: every split body's element step over
    /// all its parts in the last step and every pair's closing-speed figures (the
    /// `StepReport::part_dts` merged), for the contact pass that step left pending
    /// (empty when none is: no split group, or a `Contact` ran it). `direct`: the
    /// holders of split groups exchange their part states with each other (at the
    /// addresses of `SplitSpec::peers`) instead of through the master's `Halo`, and
    /// answer with the halo's outcome in `StepReport::halo`.
    Step {
        at: Clock,
        dt: f64,
        kin_nodes: bool,
        due: Due,
        contact: SplitFigures,
        direct: bool,
    },
    /// What an output frame shows of these bodies (held by the worker).
    Frame(Vec<u32>),
    /// The state of these bodies (held by the worker; empty: every body held), for a
    /// checkpoint. The master asks in pieces of bounded size (MAX_MESSAGE).
    States(Vec<u32>),
    /// Forget every body held, keep the definitions (a rollback to a checkpoint after a
    /// worker was lost: the checkpoint's states are loaded next).
    Reset,
    /// The worker holds the group `spec.ids` (one of its groups, no copies): split it
    /// into parts shared with other workers. Answered by `Unloaded` (the whole bodies,
    /// definitions included, for the other holders).
    Split(SplitSpec),
    /// Hold the parts `spec` gives this worker of a group another worker splits: the
    /// whole bodies at clock `at`. Without bodies: split the group held here at `at`
    /// (a split planned at the start; slot 0 is the home).
    Share {
        at: Clock,
        spec: SplitSpec,
        bodies: Vec<BodyLoad>,
    },
    /// Second (and last) exchange of a step for workers holding parts: the other
    /// holders' part states (`StepReport::parts`) of every split group this worker
    /// holds parts of. Answered by a `Report` with this worker's share of each split
    /// body's report and `part_dts`; the contact pass is left for the next Step.
    Halo(Vec<PartState>),
    /// Run the pending contact pass of the split groups now, with each split body's
    /// element step over all its parts (as the next Step would carry them): before
    /// the whole bodies are assembled (frames, checkpoints, merging back). Answered by
    /// a `Report` with `split_contacts` only.
    Contact(SplitFigures),
    /// The full states of the parts this worker computes (of every split group), for
    /// the assembly of whole bodies. Answered by `Parts`.
    Parts,
    /// The other holders' parts (`Parts`) for the groups this worker split: assemble
    /// the whole bodies (frames, states, the hash and merging back read them).
    Assemble(Vec<(u32, u32, BodyState)>),
    /// Merge every split group back: its splitting worker holds it as a group again
    /// (after an `Assemble` at this clock), the others drop their parts.
    Unsplit,
    /// The frame shares of these split bodies from the parts this worker computes (the
    /// pending contact pass has run: `Contact`), instead of an assembly. Answered by
    /// `PartFrames`.
    PartFrames(Vec<u32>),
    Shutdown(String),
}

impl Command {
    /// A Regroup without copies.
    pub fn regroup(groups: Vec<Vec<u32>>) -> Self {
        Command::Regroup {
            groups,
            copies: Vec::new(),
        }
    }
}

/// A group split over workers: its bodies (sorted), each body's part count, the
/// worker slot computing each part (`holder[i][q]`), and the receiving worker's slot.
/// Every holder cuts the bodies the same way (`partition_body` is deterministic).
/// `workers[slot]`: the worker index of each slot; `peers[slot]`: where it takes
/// direct halo connections (host:port; empty where it takes none).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SplitSpec {
    pub ids: Vec<u32>,
    pub parts: Vec<u32>,
    pub holder: Vec<Vec<u32>>,
    pub slot: u32,
    pub workers: Vec<u32>,
    pub peers: Vec<String>,
}

/// Compute time of one group in one step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GroupTime {
    /// Smallest body id of the group.
    pub first: u32,
    pub nanos: u64,
}

/// A worker's answer to Start or Step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepReport {
    pub bodies: Vec<BodyReport>,
    pub groups: Vec<GroupTime>,
    /// Wall time the worker spent on the command.
    pub compute_ns: u64,
    /// Contact statistics of the worker's groups, group after group.
    pub contacts: Vec<PairStats>,
    /// The worker's decoding of this command and encoding of its previous reply [ns]
    /// (0 in process): a part of the barrier.
    pub codec_ns: u64,
    /// History nodes of the worker's groups, group after group (empty unless asked).
    pub probes: Vec<NodeProbe>,
    /// Owned states of the parts of split groups this worker computes (a Step): the
    /// master relays them to the other holders (`Command::Halo`).
    pub parts: Vec<PartState>,
    /// Each split body's smallest element step over the parts computed here and each
    /// pair's closing-speed figures over them (a Halo): merged by the master, they go
    /// back with the next Step (`Step::contact`).
    pub part_dts: SplitFigures,
    /// This worker's share of the split groups' contact statistics from the pass the
    /// last step left pending (a Step runs it first, or a Contact), sorted by pair:
    /// each push booked by the holder owning its slave node, so the master's merge
    /// per pair (`PairStats::merge`) gives one process's figures.
    pub split_contacts: Vec<PairStats>,
    /// The step limits the split groups' contact pass set on this worker, by body id
    /// (a Contact in the step under the segment pass: its stiffening step, the
    /// minimum over the points this worker's views count); the master takes the
    /// minimum over the holders.
    pub split_limits: Vec<(u32, f64)>,
    /// A Step with `direct`: the second half of the split groups' step, after the
    /// holders exchanged their part states with each other (None when no split group
    /// is held here, or another holder's fault stopped the exchange).
    pub halo: Option<Box<Halo>>,
}

/// The outcome of a split step's second half when the holders exchange their part
/// states directly: what a `Halo` command would have been answered.
#[derive(Debug, Clone, PartialEq)]
pub enum Halo {
    /// The report a Halo command gets.
    Report(Box<StepReport>),
    /// A physical fault of a split group (as `Reply::Fault`).
    Fault {
        group_first: u32,
        fault: Fault,
        split_contacts: Option<Vec<PairStats>>,
    },
    /// The worker could not carry out the halo (as `Reply::Error`).
    Error(String),
    /// The direct exchange with another holder failed (unreachable, closed, silent,
    /// garbled): the master rolls back and relays the part states from then on.
    Lost(String),
}

impl Halo {
    /// The reply a `Halo` command would have got (Err: the direct exchange failed).
    pub fn into_reply(self) -> Result<Reply, String> {
        match self {
            Halo::Report(r) => Ok(Reply::Report(*r)),
            Halo::Fault {
                group_first,
                fault,
                split_contacts,
            } => Ok(Reply::Fault {
                group_first,
                fault,
                split_contacts,
            }),
            Halo::Error(e) => Ok(Reply::Error(e)),
            Halo::Lost(e) => Err(e),
        }
    }

    /// The halo outcome of a reply (a Report, a Fault or an Error; anything else is
    /// an error of the worker).
    pub fn from_reply(r: Reply) -> Self {
        match r {
            Reply::Report(rep) => Halo::Report(Box::new(rep)),
            Reply::Fault {
                group_first,
                fault,
                split_contacts,
            } => Halo::Fault {
                group_first,
                fault,
                split_contacts,
            },
            Reply::Error(e) => Halo::Error(e),
            _ => Halo::Error("the halo gave an unexpected reply".into()),
        }
    }
}

#[derive(Debug, Clone)]
pub enum Reply {
    Ack,
    Report(StepReport),
    /// The unloaded bodies, sorted by id.
    Unloaded(Vec<BodyLoad>),
    /// Frame data of the bodies asked for, in the order asked.
    Frame(Vec<FrameBody>),
    /// (id, state) of every body held, sorted by id.
    States(Vec<(u32, BodyState)>),
    /// (body id, part, state) of the parts this worker computes (`Parts`).
    Parts(Vec<(u32, u32, BodyState)>),
    /// The frame shares of the split bodies asked for, from the parts computed here (in
    /// body, then part order).
    PartFrames(Vec<PartFrame>),
    /// A physical fault in the group whose smallest body id is `group_first`, with this
    /// worker's share of the split groups' contact statistics from the pass the last
    /// step left pending (`StepReport::split_contacts`) when it ran to its end before
    /// the fault (None otherwise): the master then still writes that step's rows.
    Fault {
        group_first: u32,
        fault: Fault,
        split_contacts: Option<Vec<PairStats>>,
    },
    /// The command could not be carried out (a protocol or bookkeeping error).
    Error(String),
}
