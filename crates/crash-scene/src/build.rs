//! From a checked scene to core bodies: place the meshes, make the bodies, apply initial
//! motion, constraints, prescribed motion and loads; derive the contact margin; refuse
//! bodies that interpenetrate at t = 0.

use crate::context::Ctx;
use crate::error::{ErrorKind, SceneError};
use crate::globals::finite_vec;
use crate::margin::default_margin;
use crate::overlap::{check_initial_overlap, Penetration};
use crate::schema::BodySpec;
use crate::select::{dofs, select};
use crate::shape::{shape, Shape};
use crate::Scene;
use crash_core::contact::ContactConfig;
use crash_core::hash::Fnv;
use crash_core::{
    Body, CoreError, Fault, Group, NodalLoad, RunConfig, Section, Stabilization, Vec3,
    VelocityProgram,
};
use nalgebra::{Matrix3, Rotation3, Unit};

/// What a body was built from, for summaries and output metadata.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyInfo {
    /// e.g. `sphere R 0.1 m, level 5 (20480 tri)`.
    pub shape: String,
    pub material: String,
    /// Nodes with at least one fixed DOF (prescribed nodes included).
    pub fixed_nodes: usize,
    pub prescribed_nodes: usize,
    pub loaded_nodes: usize,
}

/// A scene ready to run.
#[derive(Debug, Clone)]
pub struct Built {
    pub name: String,
    /// Ids 0..n in file order.
    pub bodies: Vec<Body>,
    pub gravity: Vec3,
    pub end_time: f64,
    /// dt = safety * critical dt.
    pub safety: f64,
    pub output_interval: f64,
    pub contact: ContactConfig,
    /// The contact margin was derived (not given in the file).
    pub margin_derived: bool,
    /// Relative energy-balance error above which a finished run draws a warning.
    pub energy_limit: f64,
    /// FNV-1a of the scene file's bytes followed by each imported mesh file's bytes
    /// (body order). Command-line overrides are not included.
    pub scene_hash: u64,
    /// Per body, same order as `bodies`.
    pub info: Vec<BodyInfo>,
}

impl Built {
    /// The core driver's configuration for this scene (other fields default).
    pub fn run_config(&self) -> RunConfig {
        RunConfig {
            end_time: self.end_time,
            safety: self.safety,
            ..RunConfig::default()
        }
    }

    /// The core's critical time step at t = 0 (no safety factor) with the body id and
    /// element that set it: one force pass over a copy of the bodies (for `crash check`).
    pub fn critical_dt(&self) -> Result<(f64, u32, usize), Fault> {
        let mut g = Group::new(self.bodies.clone(), self.gravity);
        let reports = g.start()?;
        Ok(crash_core::driver::critical(&reports))
    }
}

fn rotation(ctx: &Ctx, key: &str, b: &BodySpec) -> Result<Matrix3<f64>, SceneError> {
    let Some(r) = &b.rotation else {
        return Ok(Matrix3::identity());
    };
    let axis = Vec3::from(r.axis);
    if !(axis.iter().all(|c| c.is_finite()) && axis.norm() > 0.0) {
        return Err(ctx.invalid(
            &format!("{key}.axis"),
            "must be a finite non-zero vector [x, y, z]",
        ));
    }
    if !r.angle.is_finite() {
        return Err(ctx.invalid(&format!("{key}.angle"), "must be finite (degrees)"));
    }
    Ok(Rotation3::from_axis_angle(&Unit::new_normalize(axis), r.angle.to_radians()).into_inner())
}

/// A core geometry error, located at the shape (or at the element's line in its file).
fn geometry_error(ctx: &Ctx, s: &Shape, e: CoreError) -> SceneError {
    let element = match &e {
        CoreError::NodeIndex { element, .. }
        | CoreError::Degenerate { element, .. }
        | CoreError::Warped { element, .. }
        | CoreError::NonConvex { element, .. } => Some(*element),
        _ => None,
    };
    match (&s.source, element) {
        (Some(src), Some(el)) => {
            let (tag, line) = src.element_tags.get(el).copied().unwrap_or((0, 0));
            ctx.value_error(
                ErrorKind::Geometry,
                &format!("{}.file", s.key),
                format!("{}:{line}: element tag {tag}: {e}", src.display),
            )
        }
        _ => ctx.key_error(ErrorKind::Geometry, &s.key, e),
    }
}

fn non_negative(ctx: &Ctx, key: &str, v: Option<f64>, unit: &str) -> Result<f64, SceneError> {
    let v = v.unwrap_or(0.0);
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(ctx.invalid(key, format!("must be finite and >= 0 ({unit})")))
    }
}

pub(crate) fn body(
    scene: &Scene,
    ctx: &Ctx,
    i: usize,
    b: &BodySpec,
    hash: &mut Fnv,
) -> Result<(Body, BodyInfo), SceneError> {
    let key = format!("bodies[{i}]");
    let material = scene.materials.get(&b.material).copied().ok_or_else(|| {
        ctx.value_error(
            ErrorKind::Reference,
            &format!("{key}.material"),
            "no material of that name",
        )
    })?;
    if !(b.thickness.is_finite() && b.thickness > 0.0) {
        return Err(ctx.invalid(&format!("{key}.thickness"), "must be finite and > 0 (m)"));
    }
    let s = shape(ctx, &scene.dir, i, b, hash)?;
    let local = s.mesh.nodes.clone();
    let rot = rotation(ctx, &format!("{key}.rotation"), b)?;
    let pos = finite_vec(ctx, &format!("{key}.position"), b.position)?;
    let mut mesh = s.mesh.clone();
    mesh.transform(&rot, pos);
    let mut body = Body::new(
        i as u32,
        &b.name,
        &mesh,
        Section::new(material, b.thickness),
        Stabilization::default(),
    )
    .map_err(|e| match e {
        CoreError::Thickness { .. } => {
            ctx.invalid(&format!("{key}.thickness"), "must be finite and > 0 (m)")
        }
        CoreError::Material { field, valid, .. } => {
            ctx.invalid(&format!("materials.{}.{field}", b.material), valid)
        }
        other => geometry_error(ctx, &s, other),
    })?;
    body.def_mut().mass_damping =
        non_negative(ctx, &format!("{key}.mass_damping"), b.mass_damping, "1/s")?;
    body.def_mut().contact = b.contact.unwrap_or(true);
    body.def_mut().self_contact = b.self_contact.unwrap_or(false);

    let v = finite_vec(ctx, &format!("{key}.velocity"), b.velocity)?;
    let w = finite_vec(ctx, &format!("{key}.angular_velocity"), b.angular_velocity)?;
    let com = body.centre_of_mass();
    body.set_rigid_velocity(v, w, com);

    let global = body.def.x0.clone();
    let mut info = BodyInfo {
        shape: s.describe.clone(),
        material: b.material.clone(),
        fixed_nodes: 0,
        prescribed_nodes: 0,
        loaded_nodes: 0,
    };
    for (k, f) in b.fix.iter().enumerate() {
        let fk = format!("{key}.fix[{k}]");
        let nodes = select(ctx, &format!("{fk}.select"), &f.select, &local, &global)?;
        let mask = dofs(ctx, &format!("{fk}.dofs"), f.dofs.as_ref())?;
        for n in nodes {
            body.fix(n, mask);
        }
    }
    for (k, p) in b.prescribe.iter().enumerate() {
        let pk = format!("{key}.prescribe[{k}]");
        let nodes = select(ctx, &format!("{pk}.select"), &p.select, &local, &global)?;
        let velocity = finite_vec(ctx, &format!("{pk}.velocity"), Some(p.velocity))?;
        let ramp = non_negative(ctx, &format!("{pk}.ramp"), p.ramp, "s")?;
        body.prescribe(
            &nodes,
            VelocityProgram {
                velocity,
                angular: Vec3::zeros(),
                ramp,
            },
        );
    }
    // several loads on one node are summed here: the core keeps one load per node
    let mut per_node: Vec<Option<NodalLoad>> = vec![None; body.node_count()];
    for (k, l) in b.load.iter().enumerate() {
        let lk = format!("{key}.load[{k}]");
        let nodes = select(ctx, &format!("{lk}.select"), &l.select, &local, &global)?;
        if l.force.is_none() && l.moment.is_none() {
            return Err(ctx.missing(
                &format!("{lk}.force"),
                "a load needs force (N) and/or moment (N m)",
            ));
        }
        let force = finite_vec(ctx, &format!("{lk}.force"), l.force)? / nodes.len() as f64;
        let moment = finite_vec(ctx, &format!("{lk}.moment"), l.moment)? / nodes.len() as f64;
        let t0 = non_negative(ctx, &format!("{lk}.start"), l.start, "s")?;
        let t1 = t0 + non_negative(ctx, &format!("{lk}.ramp"), l.ramp, "s")?;
        for n in nodes {
            let slot = &mut per_node[n];
            match slot {
                None => {
                    *slot = Some(NodalLoad {
                        node: n as u32,
                        force,
                        moment,
                        t0,
                        t1,
                    })
                }
                Some(prev) if prev.t0 == t0 && prev.t1 == t1 => {
                    prev.force += force;
                    prev.moment += moment;
                }
                Some(_) => {
                    return Err(ctx.invalid(
                        &format!("{lk}.select"),
                        format!("node {n} already carries a load with another start/ramp: loads on one node must share start and ramp"),
                    ))
                }
            }
        }
    }
    for l in per_node.into_iter().flatten() {
        body.add_load(l);
        info.loaded_nodes += 1;
    }
    info.fixed_nodes = body.def.fixed.iter().filter(|&&f| f != 0).count();
    info.prescribed_nodes = body
        .def
        .program
        .iter()
        .filter(|&&p| p != crash_core::body::NO_PROGRAM)
        .count();
    Ok((body, info))
}

pub fn build(scene: &Scene, ctx: &Ctx, mut hash: Fnv) -> Result<Built, SceneError> {
    let g = &scene.globals;
    let mut bodies = Vec::with_capacity(scene.spec.bodies.len());
    let mut info = Vec::with_capacity(scene.spec.bodies.len());
    for (i, b) in scene.spec.bodies.iter().enumerate() {
        let (body, inf) = body(scene, ctx, i, b, &mut hash)?;
        bodies.push(body);
        info.push(inf);
    }
    let mut contact = g.contact;
    if !g.margin_given && contact.enabled {
        contact.margin = default_margin(&bodies, g.gravity, g.end_time, g.safety);
    }
    if let Some(p) = check_initial_overlap(&bodies, &contact) {
        return Err(overlap_error(scene, ctx, &p));
    }
    Ok(Built {
        name: scene.name.clone(),
        bodies,
        gravity: g.gravity,
        end_time: g.end_time,
        safety: g.safety,
        output_interval: g.output_interval,
        contact,
        margin_derived: !g.margin_given,
        energy_limit: g.energy_limit,
        scene_hash: hash.finish(),
        info,
    })
}

/// The error for two bodies that interpenetrate at t = 0, located at the later body.
pub(crate) fn overlap_error(scene: &Scene, ctx: &Ctx, p: &Penetration) -> SceneError {
    let spec = |id: u32| &scene.spec.bodies[id as usize];
    let (a, b) = (spec(p.node_body), spec(p.segment_body));
    let later = p.node_body.max(p.segment_body) as usize;
    let key = match scene.spec.bodies[later].position {
        Some(_) => format!("bodies[{later}].position"),
        None => format!("bodies[{later}]"),
    };
    let gap = 0.5 * (a.thickness + b.thickness);
    ctx.key_error(
        ErrorKind::Geometry,
        &key,
        format!(
            "bodies \"{}\" and \"{}\" interpenetrate at t = 0: {} node(s) of \"{}\" lie closer to \"{}\" than the half-thickness sum {:.4e} m (node {} by {:.4e} m, at element {}); move them apart",
            a.name, b.name, p.nodes, a.name, b.name, gap, p.node, p.depth, p.segment
        ),
    )
}
