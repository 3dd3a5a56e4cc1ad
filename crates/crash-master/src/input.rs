//! What a distributed run needs: the bodies and run parameters (filled from
//! `crash_scene::Built`) and the master's own options.

use crate::error::MasterError;
use crash_core::contact::ContactConfig;
use crash_core::{Body, BodyBrief, RunConfig, Vec3};

/// Where the bodies come from when the master hands them to workers, one at a time.
#[derive(Debug, Clone)]
pub enum BodySource {
    /// Bodies built already (local runs, tests): moved to their workers as they are.
    Built(Vec<Option<Body>>),
    /// A planned scene: each body is built when it is handed over and dropped once
    /// sent, so the master never holds the model.
    Scene(Box<crash_scene::Scene>),
}

impl BodySource {
    /// Every body (copies of built ones; a scene's built anew), for reference runs.
    pub fn all(&self) -> Result<Vec<Body>, MasterError> {
        match self {
            BodySource::Built(bodies) => Ok(bodies.iter().flatten().cloned().collect()),
            BodySource::Scene(scene) => scene
                .build()
                .map(|b| b.bodies)
                .map_err(|e| MasterError::Input(e.to_string())),
        }
    }

    /// Body `id` (ids 0..n; a built body can be taken once).
    pub fn take(&mut self, id: u32) -> Result<Body, MasterError> {
        match self {
            BodySource::Built(bodies) => bodies
                .iter_mut()
                .find(|b| b.as_ref().is_some_and(|b| b.def.id == id))
                .and_then(Option::take)
                .ok_or_else(|| MasterError::Input(format!("body {id} is not in the input"))),
            BodySource::Scene(scene) => scene
                .body(id as usize)
                .map_err(|e| MasterError::Input(e.to_string())),
        }
    }
}

#[derive(Debug, Clone)]
pub struct RunInput {
    pub name: String,
    /// What the master keeps of each body (no nodal data).
    pub briefs: Vec<BodyBrief>,
    pub bodies: BodySource,
    pub gravity: Vec3,
    pub contact: ContactConfig,
    /// End time, safety factor, runaway limit, dt floor (the core driver's rules).
    pub config: RunConfig,
    /// Simulated time between frames [s].
    pub output_interval: f64,
    pub scene_hash: u64,
    /// matsum.csv, rcforc.csv, nodout.csv, spcforc.csv.
    pub results: ResultRequest,
}

/// When the result files are written: intervals [s] (0: never), and the history nodes
/// (body id, node index, node id of the mesh file), sorted by body and node.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ResultRequest {
    pub matsum: f64,
    pub rcforc: f64,
    pub nodout: f64,
    pub spcforc: f64,
    pub history: Vec<(u32, u32, u64)>,
}

impl ResultRequest {
    /// From a scene's `[outputs]`: matsum.csv and rcforc.csv at their interval or the
    /// frame interval (they cost the workers nothing); nodout.csv when history nodes are
    /// named, spcforc.csv when its interval is given (both need data from every step).
    pub fn of(o: &crash_scene::outputs::Outputs, output_interval: f64) -> Self {
        let mut history: Vec<(u32, u32, u64)> = o
            .history
            .iter()
            .map(|&(b, n, tag)| (b, n as u32, tag))
            .collect();
        history.sort_unstable();
        history.dedup();
        Self {
            matsum: o.matsum.unwrap_or(output_interval),
            rcforc: o.rcforc.unwrap_or(output_interval),
            nodout: if history.is_empty() {
                0.0
            } else {
                o.nodout.unwrap_or(output_interval)
            },
            spcforc: o.spcforc.unwrap_or(0.0),
            history,
        }
    }
}

/// How big a run is (for the summary).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RunSize {
    pub bodies: usize,
    pub nodes: usize,
    pub elements: usize,
}

impl RunInput {
    /// Whether the master may split this scene's groups under `mode`: the scene-wide
    /// form of the split planner's refusals (master/split.rs `plan`: no group holding a
    /// kinematic body or copy, none while history nodes are asked for). `crash run`
    /// reads it to choose between domains and shared loops.
    pub fn groups_may_split(&self, mode: SplitMode) -> bool {
        mode != SplitMode::Off
            && self.results.history.is_empty()
            && self.briefs.iter().all(|b| !b.kinematic)
    }

    /// Body names in the order of `ids` ("body ID" where the scene gave none).
    pub fn names_by_id(&self, ids: &[u32]) -> Vec<String> {
        let by_id: std::collections::BTreeMap<u32, &str> = self
            .briefs
            .iter()
            .map(|b| (b.id, b.name.as_str()))
            .collect();
        ids.iter()
            .map(|id| {
                by_id
                    .get(id)
                    .map(|n| n.to_string())
                    .filter(|n| !n.is_empty())
                    .unwrap_or_else(|| format!("body {id}"))
            })
            .collect()
    }

    /// From bodies built in this process (`crash run`, tests).
    pub fn from_built(b: crash_scene::Built) -> Self {
        let config = b.run_config();
        Self {
            name: b.name,
            briefs: b.bodies.iter().map(BodyBrief::of).collect(),
            bodies: BodySource::Built(b.bodies.into_iter().map(Some).collect()),
            gravity: b.gravity,
            contact: b.contact,
            config,
            output_interval: b.output_interval,
            scene_hash: b.scene_hash,
            results: ResultRequest::of(&b.outputs, b.output_interval),
        }
    }

    /// From a planned scene: bodies are built one at a time as they are handed to
    /// workers (`crash-master`: its memory does not grow with the model).
    pub fn from_plan(scene: crash_scene::Scene, plan: crash_scene::Plan) -> Self {
        let config = plan.run_config();
        Self {
            name: plan.name,
            briefs: plan.briefs,
            bodies: BodySource::Scene(Box::new(scene)),
            gravity: plan.gravity,
            contact: plan.contact,
            config,
            output_interval: plan.output_interval,
            scene_hash: plan.scene_hash,
            results: ResultRequest::of(&plan.outputs, plan.output_interval),
        }
    }

    pub fn size(&self) -> RunSize {
        RunSize {
            bodies: self.briefs.len(),
            nodes: self.briefs.iter().map(|b| b.nodes).sum(),
            elements: self.briefs.iter().map(|b| b.elements).sum(),
        }
    }
}

/// How group costs are estimated for balancing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CostModel {
    /// Elements + contact nodes (deterministic placement).
    Estimated,
    /// Measured per-group compute time, shared among members by their estimates.
    Measured,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunOptions {
    /// MEIM boxes are inflated by `margin_factor` x the contact margin (>= 1); the
    /// part above 1 is the motion budget between two updates (docs: the margin).
    pub margin_factor: f64,
    /// MEIM edges survive this many updates after the boxes separate.
    pub split_after: u64,
    pub cost: CostModel,
    /// Rebalance when the most and least loaded workers differ by more than this
    /// fraction of the mean load.
    pub balance_tolerance: f64,
    /// With measured costs, also try to rebalance every this many steps (0: only when
    /// groups change).
    pub rebalance_interval: u64,
    /// Hand the sink a checkpoint (`Sink::checkpoint`) after every this many steps
    /// (0: never). The last step of a run takes none. These checkpoints go to disk
    /// (`Sink::checkpoint`), and so do the timed ones below when this is set.
    pub checkpoint_every: u64,
    /// Also take a checkpoint when this much wall time has passed since the last one
    /// [s] (0: never). Every checkpoint (of either kind) is kept in memory as the point
    /// the run goes back to when a worker is lost; with neither kind, a lost worker
    /// ends the run.
    pub checkpoint_seconds: f64,
    /// When every worker was lost, wait this long for a newcomer (`join::Newcomers`)
    /// and roll back onto it [s] (0: stop at once). Runs without newcomers stop at once.
    pub rejoin_seconds: f64,
    /// Replay a worker's fault on the other workers before believing it (with a
    /// checkpoint and another live worker; `master/confirm.rs`). For workers that could
    /// lie (crash-master's); in-process workers cannot, so `crash run` leaves it off.
    pub confirm_faults: bool,
    /// Split a group larger than its share over several workers (`master/split.rs`).
    pub split: SplitMode,
}

/// When a group is split over workers by elements (issue 16 point 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SplitMode {
    /// Never: a group runs on one worker.
    #[default]
    Off,
    /// When its estimated cost exceeds the fair share (total / workers) by the balance
    /// tolerance.
    Auto,
    /// Every group that can be split, whenever there are two workers (tests).
    Always,
}

impl std::str::FromStr for SplitMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "off" => Ok(SplitMode::Off),
            "auto" => Ok(SplitMode::Auto),
            "always" => Ok(SplitMode::Always),
            _ => Err(format!("'{s}' is not off, auto or always")),
        }
    }
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            margin_factor: 2.0,
            split_after: 50,
            cost: CostModel::Measured,
            balance_tolerance: 0.1,
            rebalance_interval: 500,
            checkpoint_every: 0,
            checkpoint_seconds: 0.0,
            rejoin_seconds: 0.0,
            confirm_faults: false,
            split: SplitMode::Off,
        }
    }
}
