//! Contact parameters of a scene.

use crate::body::Body;
use crate::error::CoreError;
use serde::{Deserialize, Serialize};

/// How the penalty stiffness is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PenaltyKind {
    /// Soft constraint k = s * m* / dt^2 (m* the smaller of the node's and the segment
    /// nodes' masses, dt the pair's reference step): stable by construction.
    Soft,
    /// Element-based k = s * E/(1-nu^2) * A / L of the segment's element (plane-stress
    /// modulus, initial area A, longest edge or diagonal L); its stable step enters the
    /// global time step.
    Element,
}

/// What keeps a node from crossing a contact slab in one step at high speed
/// (docs/theory-contact.md, "Fast motion").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpeedRule {
    /// The time step of every candidate pair's bodies is limited by their closing
    /// speed (`CLOSING_FRACTION` of the contact distance per step), and the soft
    /// penalty's reference step with it; a crossing that happens anyway stops the run.
    #[default]
    LimitDt,
    /// No limit from speed: a crossing stops the run.
    Stop,
}

/// Where contact forces act (docs/theory-contact.md, "Segment pass").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactPass {
    /// Node to segment, both ways (each body's nodes against the other's segments).
    #[default]
    Nodes,
    /// Quadrature points on one body's curved segments against the other's curved
    /// surface (`SegmentSides`; soft penalty only); self pairs stay node to segment.
    Segments,
}

/// Which bodies' points the segment pass searches (docs/theory-contact.md, "One side").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SegmentSides {
    /// Per pair: one way (as `Finer`) where one surface is clearly finer (its mean
    /// initial segment area under `ONE_SIDE_RATIO` of the other's), else two way (as
    /// `Both`): meshes of about one size have no finer side, and a crush between them
    /// needs both sides' points to hold each one's folds.
    #[default]
    Auto,
    /// One way: the finer surface's points (smaller mean initial segment area, else the
    /// lower id), full weight. Exact in sliding, about half the cost of both; in a
    /// crush a sharp fold can cross the other surface between the slave's points (no
    /// point sits on a node; the crossing check stops the run).
    Finer,
    /// Two way: each body's points against the other, half the weight each.
    Both,
}

/// Under `SegmentSides::Auto`, a pair runs one way when the finer surface's mean
/// initial segment area is below this fraction of the other's (docs/theory-contact.md,
/// "One side": the crushed tube on a plate of about its mesh size, 0.98, needs both
/// sides; the floor's spheres against the plate, 0.63, and the showcase's ball, 0.14,
/// run one way).
pub const ONE_SIDE_RATIO: f64 = 0.7;

/// Most a node may close on a segment in one step, as a fraction of the contact
/// distance c = (t_node + t_segment)/2, under `SpeedRule::LimitDt`.
pub const CLOSING_FRACTION: f64 = 0.2;

/// Fraction of a pair's smallest element critical step used as the reference step of
/// the soft penalty (the industry safety factor; docs/theory-contact.md).
pub const REFERENCE_SAFETY: f64 = 0.9;

/// Largest soft penalty scale: with the elements at 0.9 of their limit (omega h = 1.8),
/// a contact spring adds (omega_c h)^2 <= 2 s, and (1.8)^2 + 2 s must stay below 4.
pub const SOFT_SCALE_LIMIT: f64 = 0.3;

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactConfig {
    /// Contact between bodies switched on.
    pub enabled: bool,
    /// Search margin [m]: half of it inflates each thickness-inflated body box (level i),
    /// it is the Verlet skin of the segment trees (level ii), and half of it is the most a
    /// node may move in one step (tunnelling guard). <= 0: each body uses its thickness.
    pub margin: f64,
    /// Penalty scale s.
    pub penalty_scale: f64,
    pub penalty: PenaltyKind,
    /// Contact damping as a fraction of critical (0 = off).
    pub damping_ratio: f64,
    /// Fast motion: limit the time step by closing speed, or only stop at a crossing.
    #[serde(default)]
    pub speed_rule: SpeedRule,
    /// Node passes or the segment pass.
    #[serde(default)]
    pub pass: ContactPass,
    /// The segment pass's sides (one way or two way).
    #[serde(default)]
    pub sides: SegmentSides,
}

impl Default for ContactConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            margin: 0.0,
            penalty_scale: 0.1,
            penalty: PenaltyKind::Soft,
            damping_ratio: 0.0,
            speed_rule: SpeedRule::LimitDt,
            pass: ContactPass::Nodes,
            sides: SegmentSides::Auto,
        }
    }
}

impl ContactConfig {
    /// The search margin of one body: `margin` if set (> 0), otherwise its thickness.
    pub fn margin_for(&self, body: &Body) -> f64 {
        self.margin_of(body.def.section.thickness)
    }

    /// The search margin of a body of the given thickness.
    pub fn margin_of(&self, thickness: f64) -> f64 {
        if self.margin > 0.0 {
            self.margin
        } else {
            thickness
        }
    }

    /// The most a node of `body` may move in one step: half its margin, so that two
    /// bodies closing at full budget cannot cross the margin between two searches.
    pub fn step_budget(&self, body: &Body) -> f64 {
        0.5 * self.margin_for(body)
    }

    /// Reject values that would make contact meaningless or unstable.
    pub fn validate(&self) -> Result<(), CoreError> {
        let bad = |field: &str, value: f64, valid: &str| CoreError::Other {
            body: "contact".into(),
            what: format!("{field} = {value} is invalid: {valid}"),
        };
        if !self.margin.is_finite() {
            return Err(bad(
                "margin",
                self.margin,
                "must be finite (m; <= 0: thickness)",
            ));
        }
        if !(self.penalty_scale.is_finite() && self.penalty_scale > 0.0) {
            return Err(bad(
                "penalty_scale",
                self.penalty_scale,
                "must be finite and > 0",
            ));
        }
        if self.penalty == PenaltyKind::Soft && self.penalty_scale > SOFT_SCALE_LIMIT {
            return Err(bad(
                "penalty_scale",
                self.penalty_scale,
                "the soft penalty is stable only for s <= 0.3 (0.1 recommended)",
            ));
        }
        if !(self.damping_ratio.is_finite() && (0.0..=1.0).contains(&self.damping_ratio)) {
            return Err(bad(
                "damping_ratio",
                self.damping_ratio,
                "must be in [0, 1]",
            ));
        }
        if self.pass == ContactPass::Segments && self.penalty != PenaltyKind::Soft {
            return Err(CoreError::Other {
                body: "contact".into(),
                what: "pass = segments needs penalty = soft (its stiffness is per area)".into(),
            });
        }
        Ok(())
    }
}
