//! crash-proto: the wire protocol of crash (package `crash.v1`, files in `proto/`) and
//! the conversions between its generated types and the domain types of crash-core.
//!
//! Domain code never touches generated types: bodies, reports and faults are converted
//! here ([`body`], [`report`]); the commands and replies of a session are converted by
//! crash-link's `wire` module, at the network edge.

pub mod body;
pub mod error;
pub mod report;

/// Generated messages, client and server of `crash.v1`.
#[allow(clippy::all, missing_debug_implementations)]
pub mod pb {
    tonic::include_proto!("crash.v1");
}

pub use body::{
    apply_state, body_from_pb, body_to_pb, def_from_pb, def_to_pb, state_from_pb, state_to_pb,
};
pub use error::ProtoError;

pub fn vec3_to_pb(v: &crash_core::Vec3) -> pb::Vec3 {
    pb::Vec3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}
