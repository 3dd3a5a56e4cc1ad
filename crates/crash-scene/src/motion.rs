//! A body's supports, prescribed motion and loads (`fix`, `prescribe`, `load`), with
//! load curves mapped onto what the solver core runs (see `curves`).

use crate::build::BodyInfo;
use crate::context::Ctx;
use crate::curves::Curve;
use crate::error::{ErrorKind, SceneError};
use crate::globals::finite_vec;
use crate::schema::BodySpec;
use crate::select::{dofs, select};
use crash_core::{Body, NodalLoad, TimeCurve, Vec3, VelocityProgram, NO_CURVE};
use std::collections::{BTreeMap, BTreeSet};

/// Positions and ids a selector picks from.
#[derive(Debug)]
pub struct Nodes<'a> {
    pub local: &'a [Vec3],
    pub global: &'a [Vec3],
    pub tags: Option<&'a [u64]>,
    /// Element ids of the mesh file (body element order: triangles, then quads).
    pub element_tags: Option<&'a [u64]>,
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

/// The body's index of curve `name` (added to the body on first use).
fn curve_index(
    ctx: &Ctx,
    key: &str,
    name: &str,
    c: &Curve,
    body: &mut Body,
    used: &mut BTreeMap<String, u32>,
) -> Result<u32, SceneError> {
    if let Some(&i) = used.get(name) {
        return Ok(i);
    }
    let i = body
        .add_curve(TimeCurve {
            points: c.points.clone(),
        })
        .map_err(|e| ctx.invalid(key, e.to_string()))?;
    used.insert(name.to_string(), i);
    Ok(i)
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
    // curves that are ramps run as ramps (as before curves existed); others as tables
    let mut used: BTreeMap<String, u32> = BTreeMap::new();
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
        let (velocity, displacement) = match (p.velocity, p.displacement) {
            (Some(v), None) => (finite_vec(ctx, &format!("{pk}.velocity"), Some(v))?, false),
            (None, Some(d)) => (
                finite_vec(ctx, &format!("{pk}.displacement"), Some(d))?,
                true,
            ),
            (Some(_), Some(_)) => {
                return Err(ctx.key_error(
                    ErrorKind::Invalid,
                    &format!("{pk}.displacement"),
                    "give either velocity or displacement, not both",
                ))
            }
            (None, None) => {
                return Err(ctx.missing(
                    &format!("{pk}.velocity"),
                    "a prescribed motion needs velocity (m/s) or displacement (m)",
                ))
            }
        };
        if displacement && p.angular_velocity.is_some() {
            return Err(ctx.key_error(
                ErrorKind::Invalid,
                &format!("{pk}.angular_velocity"),
                "a prescribed displacement holds the rotations: prescribed rotation angles are not supported",
            ));
        }
        let angular = finite_vec(ctx, &format!("{pk}.angular_velocity"), p.angular_velocity)?;
        let (scale, ramp, cid) = match (&p.curve, p.ramp) {
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
                    Some(r) if r.t0 == 0.0 => (r.value, r.t1, NO_CURVE),
                    _ => (1.0, 0.0, curve_index(ctx, &ck, name, c, body, &mut used)?),
                }
            }
            (None, r) => (
                1.0,
                non_negative(ctx, &format!("{pk}.ramp"), r, "s")?,
                NO_CURVE,
            ),
        };
        if displacement {
            // the nodes start at x0: the displacement must be 0 at t = 0
            let f0 = match &p.curve {
                Some(name) => curve(ctx, &format!("{pk}.curve"), name, curves)?.value(0.0),
                None if ramp > 0.0 => 0.0,
                None => 1.0,
            };
            if f0 != 0.0 {
                let k = if p.curve.is_some() { "curve" } else { "ramp" };
                return Err(ctx.invalid(
                    &format!("{pk}.{k}"),
                    "a prescribed displacement starts from the mesh: its curve must be 0 at t = 0 (or give a ramp > 0)",
                ));
            }
        }
        body.prescribe(
            &picked,
            VelocityProgram {
                velocity: velocity * scale,
                angular: angular * scale,
                ramp,
                curve: cid,
                displacement,
            },
        );
    }
    // loads with the same ramp on one node are summed; the core adds up the others
    let mut per_node: BTreeMap<(usize, u64, u64, u32), NodalLoad> = BTreeMap::new();
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
        let (scale, t0, t1, cid) = match &l.curve {
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
                match c.as_ramp() {
                    Some(r) => (r.value, r.t0, r.t1, NO_CURVE),
                    None => (
                        1.0,
                        0.0,
                        0.0,
                        curve_index(ctx, &ck, name, c, body, &mut used)?,
                    ),
                }
            }
            None => {
                let t0 = non_negative(ctx, &format!("{lk}.start"), l.start, "s")?;
                let t1 = t0 + non_negative(ctx, &format!("{lk}.ramp"), l.ramp, "s")?;
                (1.0, t0, t1, NO_CURVE)
            }
        };
        for node in picked {
            per_node
                .entry((node, t0.to_bits(), t1.to_bits(), cid))
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
                    curve: cid,
                });
        }
    }
    for (k, pr) in b.pressure.iter().enumerate() {
        let pk = format!("{key}.pressure[{k}]");
        if !pr.value.is_finite() {
            return Err(ctx.invalid(&format!("{pk}.value"), "must be finite (Pa)"));
        }
        let cid = match &pr.curve {
            Some(name) => {
                let ck = format!("{pk}.curve");
                let c = curve(ctx, &ck, name, curves)?;
                curve_index(ctx, &ck, name, c, body, &mut used)?
            }
            None => NO_CURVE,
        };
        let only = match &pr.elements {
            None => None,
            Some(ids) => Some(elements(ctx, &format!("{pk}.elements"), ids, body, nodes)?),
        };
        for (node, force) in pressure_forces(body, pr.value, only.as_ref()) {
            per_node
                .entry((node, 0, 0, cid))
                .and_modify(|p| p.force += force)
                .or_insert(NodalLoad {
                    node: node as u32,
                    force,
                    moment: Vec3::zeros(),
                    t0: 0.0,
                    t1: 0.0,
                    curve: cid,
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

/// Element indices (triangles, then quads) of the ids `ids` of the body's mesh file
/// (1, 2, ... for a generated shape).
fn elements(
    ctx: &Ctx,
    key: &str,
    ids: &[u64],
    body: &Body,
    nodes: &Nodes<'_>,
) -> Result<BTreeSet<usize>, SceneError> {
    let count = body.def.tris.len() + body.def.quads.len();
    let index: BTreeMap<u64, usize> = match nodes.element_tags {
        Some(tags) => tags.iter().enumerate().map(|(k, &t)| (t, k)).collect(),
        None => (0..count).map(|k| (k as u64 + 1, k)).collect(),
    };
    if ids.is_empty() {
        return Err(ctx.invalid(
            key,
            "an empty list loads nothing: leave it out for all elements",
        ));
    }
    let mut out = BTreeSet::new();
    for id in ids {
        let k = index.get(id).ok_or_else(|| {
            ctx.value_error(
                ErrorKind::Reference,
                key,
                format!("no element {id} in this body's mesh"),
            )
        })?;
        if !out.insert(*k) {
            return Err(ctx.invalid(key, format!("element {id} is named twice")));
        }
    }
    Ok(out)
}

/// Nodal forces of pressure p on every element (or those in `only`, by index: triangles,
/// then quads): -p A n / (corners) per corner, with the element's reference area A and
/// unit normal n (summed per node, node order).
pub fn pressure_forces(
    body: &Body,
    p: f64,
    only: Option<&BTreeSet<usize>>,
) -> BTreeMap<usize, Vec3> {
    let d = &*body.def;
    let x = &d.x0;
    let mut out: BTreeMap<usize, Vec3> = BTreeMap::new();
    let mut add = |nodes: &[u32], area: f64, n: Vec3| {
        let len = n.norm();
        if len > 0.0 {
            let f = n * (-p * area / (len * nodes.len() as f64));
            for &i in nodes {
                *out.entry(i as usize).or_insert_with(Vec3::zeros) += f;
            }
        }
    };
    let on = |k: usize| only.is_none_or(|o| o.contains(&k));
    let nt = d.tris.len();
    for (_, e) in d.tris.iter().enumerate().filter(|(k, _)| on(*k)) {
        let [a, b, c] = e.nodes.map(|i| x[i as usize]);
        add(&e.nodes, e.area0, (b - a).cross(&(c - a)));
    }
    for (_, e) in d.quads.iter().enumerate().filter(|(k, _)| on(nt + k)) {
        let [a, b, c, q] = e.nodes.map(|i| x[i as usize]);
        add(&e.nodes, e.area0, (c - a).cross(&(q - b)));
    }
    out
}
