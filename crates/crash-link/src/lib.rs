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
pub mod lane;
pub mod link;
pub mod peer;
pub mod poll;
pub mod spin;
pub mod text;
pub mod version;
pub mod wire;

pub use auth::{HelloFields, Secret, SecretError, SECRET_ENV};
pub use command::{BodyLoad, Command, GroupTime, Halo, Reply, Setup, SplitSpec, StepReport};
pub use link::{LinkError, WorkerLink};
pub use spin::IdleSpinner;
pub use text::escape_peer;
pub use version::{check_version, VersionError, PROTOCOL_VERSION};

/// Smallest limit on one message once a worker is admitted [bytes]. The largest real
/// message is one body's definition and state (a Load carries one body; a migration's
/// Load and Unloaded, one body per message; a checkpoint's States and a frame, pieces
/// of at most 100 000 elements): 6.6 MB for a 20 480-triangle sphere of
/// scenes/bench/million-shells.toml, 4.7 MB for its state alone (tests/tests/trust.rs
/// `largest_body_message_fits_the_limit`): 64 MiB covers bodies of about 200 000
/// elements with margin; `message_limit` raises it for larger bodies.
/// docs/reliability.md.
pub const MAX_MESSAGE: usize = 64 << 20;
/// Bytes per element allowed for a body's message (324 B/element measured for a
/// triangle mesh with its definition; 3x margin).
pub const BYTES_PER_ELEMENT: usize = 1024;
/// Upper bound of any limit (gRPC frames carry a 32-bit length).
pub const MAX_MESSAGE_CAP: usize = (1 << 31) - 1;

/// The message limit after admission for a run whose largest body has this many
/// elements: `MAX_MESSAGE`, or more for bodies beyond about 65 000 elements.
pub fn message_limit(largest_body_elements: usize) -> usize {
    largest_body_elements
        .saturating_mul(BYTES_PER_ELEMENT)
        .clamp(MAX_MESSAGE, MAX_MESSAGE_CAP)
}

/// Largest message the master accepts before a worker is admitted (its Hello).
pub const HELLO_LIMIT: usize = 4 << 10;

/// The gRPC service a master serves to its workers (and reports in grpc.health.v1).
pub const HEALTH_SERVICE: &str = crash_proto::pb::coordinator_server::SERVICE_NAME;
