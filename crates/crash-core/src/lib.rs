//! crash-core: the physics of crash.
//!
//! Explicit central-difference time integration (seed eq. 5–6) of co-rotational
//! one-point Reissner–Mindlin shells (3-node triangle, 4-node Belytschko–Lin–Tsay quad)
//! with Kelvin viscoelastic damping. No networking here: master and workers build on it.

// Index loops over the nodes of an element mirror the formulas in docs/theory.md.
#![allow(clippy::needless_range_loop)]
// `array::from_fn` is denied in the element kernels only (clippy.toml, element/mod.rs).
#![allow(clippy::disallowed_methods)]

pub mod body;
pub mod brief;
pub mod clock;
pub mod contact;
pub mod curve;
pub mod driver;
pub mod element;
pub mod energy;
pub mod error;
pub mod forces;
pub mod group;
pub mod hash;
pub mod integrate;
pub mod kinematic;
pub mod material;
pub mod mesh;
pub mod modal;
mod node_loop;
pub mod output;
pub mod partition;
pub mod probe;
pub mod shapes;
pub mod summed;
pub mod threads;

/// 3-vector of f64 (nalgebra).
pub type Vec3 = nalgebra::Vector3<f64>;

pub use body::{dof, Body, BodyDef, BodyEnergy, BodyState, NodalLoad, VelocityProgram};
pub use brief::BodyBrief;
pub use clock::Clock;
pub use curve::{TimeCurve, NO_CURVE};
pub use driver::{Run, RunConfig};
pub use element::Stabilization;
pub use energy::{EnergyLedger, EnergyTotals, KinematicWork};
pub use error::{CoreError, Fault};
pub use group::{BodyReport, Due, Group, Reaction, StageTimes};
pub use material::{Material, Section};
pub use mesh::Mesh;
pub use probe::NodeProbe;
