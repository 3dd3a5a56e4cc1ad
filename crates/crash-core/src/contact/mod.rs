//! Contact: frictionless penalty node-to-segment with a two-level search
//! (level i: body boxes; level ii: R-tree of segments per candidate pair).

pub mod config;

pub use config::{ContactConfig, PenaltyKind};
