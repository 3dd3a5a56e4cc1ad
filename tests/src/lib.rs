//! Shared fixtures of crash's cross-crate tests (this package's `tests/`) and of the
//! study: scenes, materials, the programs and the modes a run can take.
//!
//! - [`fixtures`]: the scene files of the suite and the repository's scenes;
//! - [`runs`]: a scene run in each mode (core driver, in-process workers) with its
//!   energy rows and state hash;
//! - [`procs`]: the `crash-master`, `crash-worker` and `crash` programs as child
//!   processes (bounded waits, killed on drop);
//! - [`cli`]: whole runs started as a user does, and their hash and frames.
//!
//! The process tests use the release binaries next to the test executable
//! (`target/release/`): `cargo build --release --workspace` builds them (the suite's
//! command, scripts/test.sh, does it first).
#![allow(clippy::unwrap_used)]

pub mod cli;
pub mod fixtures;
pub mod mutate;
pub mod procs;
pub mod runs;
