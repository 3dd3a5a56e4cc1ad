//! Node selectors ("all", the extreme faces/edges "x-" ... "z+" in the body's own frame,
//! boxes in global coordinates, node ids of an imported mesh, lists of these) and DOF
//! sets.

use crate::context::Ctx;
use crate::error::{ErrorKind, SceneError};
use crash_core::body::dof;
use crash_core::mesh::bounds;
use crash_core::Vec3;
use toml::Value;

/// Relative tolerance of selector comparisons (fraction of the body's size).
pub const SELECT_TOL: f64 = 1e-9;

const VALID_SELECT: &str = "valid: \"all\", \"x-\", \"x+\", \"y-\", \"y+\", \"z-\", \"z+\", { min = [x, y, z], max = [x, y, z] } (m, global), { nodes = [ids] } (node ids of the mesh file), or a list of these";

/// The nodes a selector picks, sorted and unique; an empty selection is an error.
/// `local` are the node positions in the body's own frame (before rotation and
/// translation), `global` after; `tags` the node ids of an imported mesh (None for a
/// generated shape).
pub fn select(
    ctx: &Ctx,
    key: &str,
    v: &Value,
    local: &[Vec3],
    global: &[Vec3],
    tags: Option<&[u64]>,
) -> Result<Vec<usize>, SceneError> {
    let mut picked = vec![false; local.len()];
    let body = Body {
        local,
        global,
        tags,
    };
    pick(ctx, key, v, &body, &mut picked)?;
    let out: Vec<usize> = picked
        .iter()
        .enumerate()
        .filter(|p| *p.1)
        .map(|p| p.0)
        .collect();
    if out.is_empty() {
        let (lo, hi) = bounds(global);
        return Err(ctx.invalid(
            key,
            format!(
                "selects no node (the body spans [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}] m)",
                lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
            ),
        ));
    }
    Ok(out)
}

/// What a selector picks from.
#[derive(Debug)]
struct Body<'a> {
    local: &'a [Vec3],
    global: &'a [Vec3],
    tags: Option<&'a [u64]>,
}

/// `{ nodes = [ids] }`: nodes of an imported mesh by their id in the file.
fn pick_ids(
    ctx: &Ctx,
    key: &str,
    v: &Value,
    tags: Option<&[u64]>,
    out: &mut [bool],
) -> Result<(), SceneError> {
    let Some(tags) = tags else {
        return Err(ctx.invalid(
            key,
            "node ids select nodes of an imported mesh (mesh.file); this body's mesh is generated: use a face or a box",
        ));
    };
    let ids = v.as_array().filter(|a| !a.is_empty()).ok_or_else(|| {
        ctx.value_error(
            ErrorKind::WrongType,
            key,
            "wrong type: must be a non-empty array of node ids (integers)",
        )
    })?;
    let index: std::collections::HashMap<u64, usize> =
        tags.iter().enumerate().map(|(i, &t)| (t, i)).collect();
    for (k, id) in ids.iter().enumerate() {
        let ik = format!("{key}[{k}]");
        let n = id.as_integer().ok_or_else(|| {
            ctx.value_error(
                ErrorKind::WrongType,
                &ik,
                "wrong type: a node id is an integer",
            )
        })?;
        let i = u64::try_from(n)
            .ok()
            .and_then(|t| index.get(&t))
            .ok_or_else(|| {
                ctx.invalid(
                    &ik,
                    format!("node {n} is not a node of this body's mesh (ids of the mesh file, used by its elements)"),
                )
            })?;
        out[*i] = true;
    }
    Ok(())
}

fn pick(
    ctx: &Ctx,
    key: &str,
    v: &Value,
    body: &Body<'_>,
    out: &mut [bool],
) -> Result<(), SceneError> {
    let (local, global) = (body.local, body.global);
    match v {
        Value::String(s) => {
            if s == "all" {
                out.iter_mut().for_each(|p| *p = true);
                return Ok(());
            }
            let (axis, max) = match s.as_str() {
                "x-" => (0, false),
                "x+" => (0, true),
                "y-" => (1, false),
                "y+" => (1, true),
                "z-" => (2, false),
                "z+" => (2, true),
                _ => return Err(ctx.invalid(key, format!("unknown selector; {VALID_SELECT}"))),
            };
            let (lo, hi) = bounds(local);
            let tol = SELECT_TOL * (hi - lo).norm().max(f64::MIN_POSITIVE);
            let target = if max { hi[axis] } else { lo[axis] };
            for (p, x) in out.iter_mut().zip(local) {
                if (x[axis] - target).abs() <= tol {
                    *p = true;
                }
            }
            Ok(())
        }
        Value::Table(t) if t.contains_key("nodes") => {
            if let Some(k) = t.keys().find(|k| *k != "nodes") {
                return Err(ctx.key_error(
                    ErrorKind::UnknownKey,
                    &format!("{key}.{k}"),
                    "a node-id selector has the one key nodes (use a list of selectors to combine it with a box)",
                ));
            }
            pick_ids(ctx, &format!("{key}.nodes"), &t["nodes"], body.tags, out)
        }
        Value::Table(t) => {
            for k in t.keys() {
                if k != "min" && k != "max" {
                    return Err(ctx.key_error(
                        ErrorKind::UnknownKey,
                        &format!("{key}.{k}"),
                        "unknown key in a box selector; valid keys: min, max (or nodes alone)",
                    ));
                }
            }
            let lo = vector(ctx, &format!("{key}.min"), t.get("min"))?;
            let hi = vector(ctx, &format!("{key}.max"), t.get("max"))?;
            for d in 0..3 {
                if lo[d] > hi[d] {
                    return Err(ctx.invalid(
                        &format!("{key}.max"),
                        format!(
                            "max[{d}] = {} is below min[{d}] = {}: must be >= min",
                            hi[d], lo[d]
                        ),
                    ));
                }
            }
            let (blo, bhi) = bounds(global);
            let tol = SELECT_TOL * (bhi - blo).norm().max(f64::MIN_POSITIVE);
            for (p, x) in out.iter_mut().zip(global) {
                if (0..3).all(|d| x[d] >= lo[d] - tol && x[d] <= hi[d] + tol) {
                    *p = true;
                }
            }
            Ok(())
        }
        Value::Array(items) => {
            if items.is_empty() {
                return Err(ctx.invalid(
                    key,
                    format!("an empty list selects nothing; {VALID_SELECT}"),
                ));
            }
            for (i, item) in items.iter().enumerate() {
                pick(ctx, &format!("{key}[{i}]"), item, body, out)?;
            }
            Ok(())
        }
        _ => Err(ctx.value_error(
            ErrorKind::WrongType,
            key,
            format!("wrong type: {VALID_SELECT}"),
        )),
    }
}

/// A 3-vector of numbers (integers accepted) under `key`.
pub fn vector(ctx: &Ctx, key: &str, v: Option<&Value>) -> Result<Vec3, SceneError> {
    let v = v.ok_or_else(|| ctx.missing(key, "give [x, y, z] in m"))?;
    let bad = || {
        ctx.value_error(
            ErrorKind::WrongType,
            key,
            "wrong type: must be an array of 3 numbers [x, y, z]",
        )
    };
    let a = v.as_array().filter(|a| a.len() == 3).ok_or_else(bad)?;
    let mut out = Vec3::zeros();
    for (d, x) in a.iter().enumerate() {
        out[d] = match x {
            Value::Float(f) => *f,
            Value::Integer(i) => *i as f64,
            _ => return Err(bad()),
        };
        if !out[d].is_finite() {
            return Err(ctx.invalid(key, "components must be finite"));
        }
    }
    Ok(out)
}

const VALID_DOFS: &str = "valid: \"all\", \"translations\", \"rotations\", or a list of \"x\", \"y\", \"z\", \"rx\", \"ry\", \"rz\"";

/// DOF bit mask (crash_core::body::dof) of a `dofs` value; absent means all.
pub fn dofs(ctx: &Ctx, key: &str, v: Option<&Value>) -> Result<u8, SceneError> {
    let one = |s: &str| -> Option<u8> {
        Some(match s {
            "all" => dof::ALL,
            "translations" => dof::TRANSLATIONS,
            "rotations" => dof::ROTATIONS,
            "x" => dof::X,
            "y" => dof::Y,
            "z" => dof::Z,
            "rx" => dof::RX,
            "ry" => dof::RY,
            "rz" => dof::RZ,
            _ => return None,
        })
    };
    match v {
        None => Ok(dof::ALL),
        Some(Value::String(s)) => {
            one(s).ok_or_else(|| ctx.invalid(key, format!("unknown DOF set; {VALID_DOFS}")))
        }
        Some(Value::Array(items)) if !items.is_empty() => {
            let mut mask = 0;
            for (i, item) in items.iter().enumerate() {
                let k = format!("{key}[{i}]");
                let s = item.as_str().ok_or_else(|| {
                    ctx.value_error(
                        ErrorKind::WrongType,
                        &k,
                        format!("wrong type: {VALID_DOFS}"),
                    )
                })?;
                mask |=
                    one(s).ok_or_else(|| ctx.invalid(&k, format!("unknown DOF; {VALID_DOFS}")))?;
            }
            Ok(mask)
        }
        Some(_) => Err(ctx.value_error(
            ErrorKind::WrongType,
            key,
            format!("wrong type: {VALID_DOFS}"),
        )),
    }
}
