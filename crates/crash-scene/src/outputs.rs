//! `[outputs]`: result intervals beyond the frames (named after the LS-DYNA files they
//! stand for) and the nodes whose histories are wanted, and how the frames are stored
//! (`precision`, `compression`). Parsed and checked here and handed over in
//! `Built::outputs`; the run writes matsum.csv, rcforc.csv, nodout.csv and spcforc.csv
//! from them (`crash_master::ResultRequest`).

use crate::context::Ctx;
use crate::error::{ErrorKind, SceneError};
use crate::schema::SceneFile;

/// Checked output requests (intervals in s; history nodes as body id and node index).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Outputs {
    pub glstat: Option<f64>,
    pub matsum: Option<f64>,
    pub rcforc: Option<f64>,
    pub nodout: Option<f64>,
    pub spcforc: Option<f64>,
    /// (body id, node index in the body, node id in its mesh file).
    pub history: Vec<(u32, usize, u64)>,
    /// Frames store their float arrays as Float32 (`precision = "f32"`).
    pub frames_f32: bool,
    /// Frames are not compressed (`compression = "none"`).
    pub frames_uncompressed: bool,
}

/// `precision` and `compression` as flags (f32, uncompressed).
fn frame_storage(ctx: &Ctx, s: &SceneFile) -> Result<(bool, bool), SceneError> {
    let o = &s.outputs;
    let f32 = match o.precision.as_deref() {
        None | Some("f64") => false,
        Some("f32") => true,
        Some(_) => {
            return Err(ctx.invalid(
                "outputs.precision",
                "must be \"f64\" (default, every bit kept) or \"f32\" (half the size)",
            ))
        }
    };
    let raw = match o.compression.as_deref() {
        None | Some("zlib") => false,
        Some("none") => true,
        Some(_) => {
            return Err(ctx.invalid(
                "outputs.compression",
                "must be \"zlib\" (default) or \"none\"",
            ))
        }
    };
    Ok((f32, raw))
}

/// Intervals finite and > 0, history bodies named (before the meshes exist).
pub fn check(ctx: &Ctx, s: &SceneFile) -> Result<(), SceneError> {
    frame_storage(ctx, s)?;
    let o = &s.outputs;
    for (name, v) in [
        ("glstat", o.glstat),
        ("matsum", o.matsum),
        ("rcforc", o.rcforc),
        ("nodout", o.nodout),
        ("spcforc", o.spcforc),
    ] {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0) {
                return Err(ctx.invalid(&format!("outputs.{name}"), "must be finite and > 0 (s)"));
            }
        }
    }
    for (k, h) in o.history.iter().enumerate() {
        if !s.bodies.iter().any(|b| b.name == h.body) {
            return Err(ctx.value_error(
                ErrorKind::Reference,
                &format!("outputs.history[{k}].body"),
                "no body of that name",
            ));
        }
        if h.nodes.is_empty() {
            return Err(ctx.invalid(
                &format!("outputs.history[{k}].nodes"),
                "list at least one node id",
            ));
        }
    }
    Ok(())
}

/// Resolve the history nodes against the built bodies (`tags[i]`: node ids of body i's
/// mesh file, None for a generated shape).
pub fn resolve(
    ctx: &Ctx,
    s: &SceneFile,
    ids: &[u32],
    tags: &[Option<Vec<u64>>],
) -> Result<Outputs, SceneError> {
    let o = &s.outputs;
    let mut history = Vec::new();
    for (k, h) in o.history.iter().enumerate() {
        let key = format!("outputs.history[{k}].nodes");
        let Some(i) = s.bodies.iter().position(|b| b.name == h.body) else {
            continue; // checked in `check`
        };
        let Some(t) = &tags[i] else {
            return Err(ctx.invalid(
                &key,
                format!(
                    "body \"{}\" has a generated mesh: node ids name nodes of a mesh file",
                    h.body
                ),
            ));
        };
        let index: std::collections::HashMap<u64, usize> =
            t.iter().enumerate().map(|(n, &id)| (id, n)).collect();
        for (j, &id) in h.nodes.iter().enumerate() {
            let n = u64::try_from(id)
                .ok()
                .and_then(|u| index.get(&u))
                .ok_or_else(|| {
                    ctx.invalid(
                        &format!("{key}[{j}]"),
                        format!("node {id} is not a node of body \"{}\"", h.body),
                    )
                })?;
            history.push((ids[i], *n, id as u64));
        }
    }
    let (frames_f32, frames_uncompressed) = frame_storage(ctx, s)?;
    Ok(Outputs {
        frames_f32,
        frames_uncompressed,
        glstat: o.glstat,
        matsum: o.matsum,
        rcforc: o.rcforc,
        nodout: o.nodout,
        spcforc: o.spcforc,
        history,
    })
}
