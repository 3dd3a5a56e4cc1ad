//! crash-proto: Wire protocol of crash (gRPC, crash.v1) and conversions to and from core types.
