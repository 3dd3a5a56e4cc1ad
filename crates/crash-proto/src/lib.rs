//! crash-proto: the wire protocol of crash (package crash.v1) and conversions.

/// Generated messages, client and server of crash.v1.
#[allow(clippy::all, missing_debug_implementations)]
pub mod pb {
    tonic::include_proto!("crash.v1");
}
