//! Shell elements: the 3-node co-rotational Reissner–Mindlin triangle and the 4-node
//! Belytschko–Lin–Tsay quad, both one-point, sharing the plate part in `plate`.
//!
//! Each element kernel is a pure function of the element's reference data, the current
//! nodal positions and half-step velocities, and its resultant state: it updates the
//! state and writes per-node internal forces and moments into its own slots (no shared
//! accumulation, so results do not depend on thread order).
//!
//! No `array::from_fn` here (clippy.toml): its closure is not inlined into the SIMD
//! entry points, which turned the quad's vector arithmetic into calls.

#![deny(clippy::disallowed_methods)]

pub mod batch;
pub mod membrane;
pub mod plate;
pub mod quad;
pub mod real;
pub mod reference;
pub mod simd;
pub mod tri;

pub use quad::QuadElem;
pub use tri::TriElem;

use serde::{Deserialize, Serialize};

/// Rate-form resultants in the element's co-rotational frame: bending moments per unit
/// length (Mxx, Myy, Mxy), transverse shear forces per unit length (Qx, Qy) and the
/// drilling stress (moment per unit area).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ShellState {
    pub m: [f64; 3],
    pub q: [f64; 2],
    pub drill: f64,
}

/// Rate-form hourglass resultants of a quad: out-of-plane (w) and rotational (theta x, y).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct HourglassState {
    pub w: f64,
    pub th: [f64; 2],
}

/// Per-node internal force (x, y, z) and moment (x, y, z) in global axes.
pub type Slot = [f64; 6];

/// What one element contributes to its body's per-step sums.
#[derive(Debug, Clone, Copy, Default)]
pub struct ElemEnergy {
    /// Elastic strain energy (membrane + bending + shear + drilling).
    pub internal: f64,
    /// Hourglass energy (quads).
    pub hourglass: f64,
}

/// Geometric failure of an element at the current configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ElemFailure {
    /// Current area / initial area below `COLLAPSE_RATIO` (or non-finite).
    Collapsed { ratio: f64 },
    /// A quad corner turned inside out.
    Inverted { corner: usize },
}

/// An element whose area shrank below this fraction of its initial area stops the run.
pub const COLLAPSE_RATIO: f64 = 1e-3;

/// Hourglass and drilling coefficients (fractions of the element's natural stiffness).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stabilization {
    /// In-plane hourglass stiffness coefficient r_m.
    pub hourglass_membrane: f64,
    /// Out-of-plane (w) hourglass coefficient r_w.
    pub hourglass_w: f64,
    /// Rotational hourglass coefficient r_theta.
    pub hourglass_rotation: f64,
    /// Drilling stiffness coefficient r_d (fraction of G t).
    pub drilling: f64,
}

impl Default for Stabilization {
    fn default() -> Self {
        Self {
            hourglass_membrane: 0.05,
            hourglass_w: 0.05,
            hourglass_rotation: 0.05,
            drilling: 0.1,
        }
    }
}
