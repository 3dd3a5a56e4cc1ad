//! `crash study`: the verification suite (error against wall time, observed orders of
//! convergence, docs/verification.md) and the stability matrix (stiff and extreme
//! cases, docs/stability.md).

pub mod build;
pub mod cases;
pub mod cli;
pub mod contact;
pub mod ladder;
pub mod looprun;
pub mod matrix;
pub mod outcome;
pub mod report;
pub mod scenarios;
pub mod stability_report;
pub mod structural;
pub mod verify;
