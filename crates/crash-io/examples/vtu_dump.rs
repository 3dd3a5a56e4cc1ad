//! Print what crash's own reader (`read_vtu`) finds in a .vtu, as JSON: counts, time,
//! step and the point arrays. The meshio check (tests/crosscheck/vtu_meshio.py)
//! compares another reader against it.
//!
//!   target/release/examples/vtu_dump frames/frame_000003.vtu

use std::process::ExitCode;

fn main() -> ExitCode {
    let Some(path) = std::env::args_os().nth(1) else {
        eprintln!("usage: vtu_dump FILE.vtu");
        return ExitCode::from(2);
    };
    let frame = match crash_io::read_vtu(std::path::Path::new(&path)) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("vtu_dump: {e}");
            return ExitCode::FAILURE;
        }
    };
    let flat = |f: &dyn Fn(&crash_io::FrameBody) -> Vec<f64>| -> Vec<f64> {
        frame.bodies.iter().flat_map(f).collect()
    };
    let out = serde_json::json!({
        "time": frame.time,
        "step": frame.step,
        "points": frame.node_count(),
        "cells": frame.element_count(),
        "triangles": frame.bodies.iter().map(|b| b.tris.len()).sum::<usize>(),
        "quads": frame.bodies.iter().map(|b| b.quads.len()).sum::<usize>(),
        "displacement": flat(&|b| b.x.iter().zip(&b.x0).flat_map(|(x, x0)| {
            let u = x - x0;
            [u.x, u.y, u.z]
        }).collect()),
        "points_xyz": flat(&|b| b.x.iter().flat_map(|p| [p.x, p.y, p.z]).collect()),
        "von_mises_top": flat(&|b| b.von_mises_top.clone()),
    });
    println!("{out}");
    ExitCode::SUCCESS
}
