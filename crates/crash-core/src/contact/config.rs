//! Contact parameters of a scene.

use serde::{Deserialize, Serialize};

/// How the penalty stiffness is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PenaltyKind {
    /// Soft constraint k = s * m* / dt^2 (m* the smaller of the node's and the segment
    /// nodes' masses): stable by construction.
    Soft,
    /// Element-based k = s * K A / L of the segment's element (membrane modulus K).
    Element,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactConfig {
    /// Contact between bodies switched on.
    pub enabled: bool,
    /// Search margin [m] added to thickness-inflated boxes (level i) and capture boxes
    /// (level ii); also the Verlet skin of the segment trees.
    pub margin: f64,
    /// Penalty scale s.
    pub penalty_scale: f64,
    pub penalty: PenaltyKind,
    /// Contact damping as a fraction of critical (0 = off).
    pub damping_ratio: f64,
}

impl Default for ContactConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            margin: 0.0,
            penalty_scale: 0.1,
            penalty: PenaltyKind::Soft,
            damping_ratio: 0.0,
        }
    }
}
