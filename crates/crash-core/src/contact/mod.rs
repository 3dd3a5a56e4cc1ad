//! Contact: frictionless penalty node-to-segment with a two-level search
//! (level i: body boxes; level ii: R-tree of segments per body, queried per candidate
//! pair). Theory and rules: docs/theory-contact.md.

pub mod broad;
pub mod config;
pub mod curved;
pub mod figures;
pub mod forest;
pub mod narrow;
pub mod overlap;
pub(crate) mod passes;
pub mod quadrature;
pub(crate) mod reach;
pub mod segment;
pub(crate) mod segpair;
pub mod smooth;
pub mod speeds;
pub mod stage;
pub mod stats;
pub mod stiffening;
pub mod surface;
pub mod sweep;
pub mod verlet;

pub use broad::{candidate_pairs, BodyBox};
pub use config::{
    ContactConfig, ContactPass, PenaltyKind, SegmentSides, SpeedRule, CLOSING_FRACTION,
    ONE_SIDE_RATIO, REFERENCE_SAFETY, SOFT_SCALE_LIMIT,
};
pub use overlap::{initial_penetrations, Inside, Penetration};
pub use segment::{project, segments, Projection, Segment};
pub use stage::{body_bounds, check_moves, contact_forces, ContactState};
pub use stats::{KinLoad, PairStats, Tally};
