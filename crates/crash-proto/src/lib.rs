//! crash-proto: the wire protocol of crash (package `crash.v1`, files in `proto/`) and
//! the conversions between its generated types and the domain types of crash-core.
//!
//! Domain code never touches generated types: the master and the workers speak
//! [`Command`] / [`Reply`] (plain Rust, moved without serialization in local mode) and
//! convert at the network edge with the functions of [`body`], [`report`] and [`msg`].

pub mod body;
pub mod error;
pub mod msg;
pub mod report;

/// Generated messages, client and server of `crash.v1`.
#[allow(clippy::all, missing_debug_implementations)]
pub mod pb {
    tonic::include_proto!("crash.v1");
}

pub use body::{apply_state, body_from_pb, body_to_pb, state_to_pb};
pub use error::ProtoError;
pub use msg::{Command, GroupTime, Reply, Setup, StepReport};

/// Version of the master <-> worker protocol. A worker and a master with different
/// versions refuse each other (the master ends the stream with FAILED_PRECONDITION).
/// Raise it whenever a message changes meaning.
pub const PROTOCOL_VERSION: u32 = 1;
