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

pub mod auth;
pub mod command;
pub mod link;
pub mod text;
pub mod version;
pub mod wire;

pub use auth::{HelloFields, Secret, SecretError, SECRET_ENV};
pub use command::{BodyLoad, Command, GroupTime, Reply, Setup, StepReport};
pub use link::{LinkError, WorkerLink};
pub use text::escape_peer;
pub use version::{check_version, VersionError, PROTOCOL_VERSION};

/// Largest message either end decodes once a worker is admitted [bytes]. The largest
/// real message is one body's definition and state (a Load carries one body; a
/// migration's Load and Unloaded, and a checkpoint's States, one body per message):
/// 6.6 MB for a 20 480-triangle sphere of scenes/bench/million-shells.toml (4.7 MB
/// for its state alone)
/// (tests/tests/trust.rs `largest_body_message_fits_the_limit`), so 64 MiB leaves
/// room for bodies of about 200 000 elements. docs/reliability.md.
pub const MAX_MESSAGE: usize = 64 << 20;
/// Largest message the master accepts before a worker is admitted (its Hello).
pub const HELLO_LIMIT: usize = 4 << 10;

/// The gRPC service a master serves to its workers (and reports in grpc.health.v1).
pub const HEALTH_SERVICE: &str = crash_proto::pb::coordinator_server::SERVICE_NAME;
