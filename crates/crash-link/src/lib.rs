//! crash-link: what the master and a worker say to each other.
//!
//! [`Command`] and [`Reply`] are plain domain values: in local mode they move between
//! the master loop and in-process workers without serialization; over gRPC they are
//! converted at the edge by [`wire`]. [`WorkerLink`] is how the master talks to any
//! worker. [`check_version`] is the handshake rule both ends apply.
//!
//! Dependencies: crash-core (bodies, reports, faults, the clock), crash-io (output
//! frames), crash-proto (generated wire types). crash-master and crash-worker both
//! depend on this crate and never on each other.

pub mod command;
pub mod link;
pub mod version;
pub mod wire;

pub use command::{BodyLoad, Command, GroupTime, Reply, Setup, StepReport};
pub use link::{LinkError, WorkerLink};
pub use version::{check_version, VersionError, PROTOCOL_VERSION};

/// The gRPC service a master serves to its workers (and reports in grpc.health.v1).
pub const HEALTH_SERVICE: &str = crash_proto::pb::coordinator_server::SERVICE_NAME;
