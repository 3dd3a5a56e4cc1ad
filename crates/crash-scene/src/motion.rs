//! A body's supports, prescribed motion and loads (`fix`, `prescribe`, `load`), with
//! load curves mapped onto what the solver core runs (see `curves`).

use crate::build::BodyInfo;
use crate::context::Ctx;
use crate::curves::Curve;
use crate::error::{ErrorKind, SceneError};
use crate::globals::finite_vec;
use crate::schema::BodySpec;
use crate::select::{dofs, select};
use crash_core::{Body, NodalLoad, Vec3, VelocityProgram};
use std::collections::{BTreeMap, BTreeSet};

/// Positions and ids a selector picks from.
#[derive(Debug)]
pub struct Nodes<'a> {
    pub local: &'a [Vec3],
    pub global: &'a [Vec3],
    pub tags: Option<&'a [u64]>,
}

pub fn non_negative(ctx: &Ctx, key: &str, v: Option<f64>, unit: &str) -> Result<f64, SceneError> {
    let v = v.unwrap_or(0.0);
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(ctx.invalid(key, format!("must be finite and >= 0 ({unit})")))
    }
}

/// The curve named at `key` (its existence is checked when the scene is parsed).
fn curve<'a>(
    ctx: &Ctx,
    key: &str,
    name: &str,
    curves: &'a BTreeMap<String, Curve>,
) -> Result<&'a Curve, SceneError> {
    curves.get(name).ok_or_else(|| {
        ctx.value_error(
            ErrorKind::Reference,
            key,
            "no curve of that name in [curves]",
        )
    })
}

fn unsupported(ctx: &Ctx, key: &str, name: &str, c: &Curve, core: &str) -> SceneError {
    let owner = key.strip_suffix(".curve").unwrap_or(key);
    ctx.value_error(
        ErrorKind::Unsupported,
        key,
        format!(
            "load curve \"{name}\" on {owner} is parsed but not yet supported by the solver core ({}): {core}",
            c.describe()
        ),
    )
}

/// Apply `fix`, `prescribe` and `load` of body spec `b` (key `key`) to `body`.
pub fn apply(
    ctx: &Ctx,
    key: &str,
    b: &BodySpec,
    body: &mut Body,
    nodes: &Nodes<'_>,
    curves: &BTreeMap<String, Curve>,
    info: &mut BodyInfo,
) -> Result<(), SceneError> {
    let pick = |k: &str, v: &toml::Value| select(ctx, k, v, nodes.local, nodes.global, nodes.tags);
    for (k, f) in b.fix.iter().enumerate() {
        let fk = format!("{key}.fix[{k}]");
        let picked = pick(&format!("{fk}.select"), &f.select)?;
        let mask = dofs(ctx, &format!("{fk}.dofs"), f.dofs.as_ref())?;
        for n in picked {
            body.fix(n, mask);
        }
    }
    for (k, p) in b.prescribe.iter().enumerate() {
        let pk = format!("{key}.prescribe[{k}]");
        let picked = pick(&format!("{pk}.select"), &p.select)?;
        let velocity = finite_vec(ctx, &format!("{pk}.velocity"), Some(p.velocity))?;
        let angular = finite_vec(ctx, &format!("{pk}.angular_velocity"), p.angular_velocity)?;
        let (scale, ramp) = match (&p.curve, p.ramp) {
            (Some(_), Some(_)) => {
                return Err(ctx.key_error(
                    ErrorKind::Invalid,
                    &format!("{pk}.ramp"),
                    "give either ramp or curve, not both",
                ))
            }
            (Some(name), None) => {
                let ck = format!("{pk}.curve");
                let c = curve(ctx, &ck, name, curves)?;
                match c.as_ramp() {
                    Some(r) if r.t0 == 0.0 => (r.value, r.t1),
                    _ => return Err(unsupported(ctx, &ck, name, c,
                        "a prescribed velocity can only rise linearly from 0 at t = 0 and then stay constant (or be constant from the start)")),
                }
            }
            (None, r) => (1.0, non_negative(ctx, &format!("{pk}.ramp"), r, "s")?),
        };
        body.prescribe(
            &picked,
            VelocityProgram {
                velocity: velocity * scale,
                angular: angular * scale,
                ramp,
            },
        );
    }
    // loads with the same ramp on one node are summed; the core adds up the others
    let mut per_node: BTreeMap<(usize, u64, u64), NodalLoad> = BTreeMap::new();
    for (k, l) in b.load.iter().enumerate() {
        let lk = format!("{key}.load[{k}]");
        let picked = pick(&format!("{lk}.select"), &l.select)?;
        if l.force.is_none() && l.moment.is_none() {
            return Err(ctx.missing(
                &format!("{lk}.force"),
                "a load needs force (N) and/or moment (N m)",
            ));
        }
        let n = picked.len() as f64;
        let force = finite_vec(ctx, &format!("{lk}.force"), l.force)? / n;
        let moment = finite_vec(ctx, &format!("{lk}.moment"), l.moment)? / n;
        let (scale, t0, t1) = match &l.curve {
            Some(name) => {
                if let Some(other) = [("start", l.start), ("ramp", l.ramp)]
                    .iter()
                    .find(|x| x.1.is_some())
                {
                    return Err(ctx.key_error(
                        ErrorKind::Invalid,
                        &format!("{lk}.{}", other.0),
                        "give either start and ramp, or curve",
                    ));
                }
                let ck = format!("{lk}.curve");
                let c = curve(ctx, &ck, name, curves)?;
                let r = c.as_ramp().ok_or_else(|| unsupported(ctx, &ck, name, c,
                    "a nodal load can only be 0 until t0, rise linearly to its value at t1 and then stay constant"))?;
                (r.value, r.t0, r.t1)
            }
            None => {
                let t0 = non_negative(ctx, &format!("{lk}.start"), l.start, "s")?;
                let t1 = t0 + non_negative(ctx, &format!("{lk}.ramp"), l.ramp, "s")?;
                (1.0, t0, t1)
            }
        };
        for node in picked {
            per_node
                .entry((node, t0.to_bits(), t1.to_bits()))
                .and_modify(|p| {
                    p.force += force * scale;
                    p.moment += moment * scale;
                })
                .or_insert(NodalLoad {
                    node: node as u32,
                    force: force * scale,
                    moment: moment * scale,
                    t0,
                    t1,
                });
        }
    }
    let loaded: BTreeSet<usize> = per_node.keys().map(|k| k.0).collect();
    info.loaded_nodes = loaded.len();
    for l in per_node.into_values() {
        body.add_load(l);
    }
    Ok(())
}
