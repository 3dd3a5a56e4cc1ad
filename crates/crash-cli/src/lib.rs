//! crash-cli: the `crash` command. `crash run` is the local (embedded) mode of the
//! master loop: in-process workers, no network, no serialization.

pub mod check;
pub mod progress;
pub mod run;
pub mod study;
