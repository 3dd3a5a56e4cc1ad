//! What a distributed run needs: the bodies and run parameters (filled from
//! `crash_scene::Built`) and the master's own options.

use crash_core::contact::ContactConfig;
use crash_core::{Body, RunConfig, Vec3};

#[derive(Debug, Clone)]
pub struct RunInput {
    pub name: String,
    pub bodies: Vec<Body>,
    pub gravity: Vec3,
    pub contact: ContactConfig,
    /// End time, safety factor, runaway limit, dt floor (the core driver's rules).
    pub config: RunConfig,
    /// Simulated time between frames [s].
    pub output_interval: f64,
    pub scene_hash: u64,
}

/// How big a run is (for the summary).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RunSize {
    pub bodies: usize,
    pub nodes: usize,
    pub elements: usize,
}

impl RunInput {
    pub fn size(&self) -> RunSize {
        RunSize {
            bodies: self.bodies.len(),
            nodes: self.bodies.iter().map(Body::node_count).sum(),
            elements: self.bodies.iter().map(Body::element_count).sum(),
        }
    }

    pub fn from_built(b: crash_scene::Built) -> Self {
        let config = b.run_config();
        Self {
            name: b.name,
            bodies: b.bodies,
            gravity: b.gravity,
            contact: b.contact,
            config,
            output_interval: b.output_interval,
            scene_hash: b.scene_hash,
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
    /// (0: never). The last step of a run takes none.
    pub checkpoint_every: u64,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            margin_factor: 2.0,
            split_after: 50,
            cost: CostModel::Measured,
            balance_tolerance: 0.25,
            rebalance_interval: 500,
            checkpoint_every: 0,
        }
    }
}
