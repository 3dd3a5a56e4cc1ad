//! From a checked scene to core bodies: plan the meshes and check the memory they need
//! against the machine, generate or import them, place them, make the bodies, apply
//! initial motion, constraints, prescribed motion and loads; derive the contact margin;
//! refuse bodies that interpenetrate at t = 0.

use crate::context::Ctx;
use crate::curves::Curve;
use crate::error::{ErrorKind, SceneError};
use crate::globals::finite_vec;
use crate::margin::{default_margin, dt_estimate};
use crate::memory::{self, Counts};
use crate::motion::{self, non_negative, Nodes};
use crate::outputs::{self, Outputs};
use crate::overlap::{check_initial_overlap, Penetration};
use crate::schema::BodySpec;
use crate::shape::{plan, Planned, Shape};
use crate::Scene;
use crash_core::contact::ContactConfig;
use crash_core::hash::Fnv;
use crash_core::{Body, CoreError, Fault, Group, RunConfig, Section, Stabilization, Vec3};
use nalgebra::{Matrix3, Rotation3, Unit};
use std::collections::BTreeMap;

/// An output interval below the time step estimate writes a frame every step; values
/// below this fraction of the estimate are raised to it, so that the frame scheduler
/// (which counts output times one at a time) never loops once per interval.
pub const OUTPUT_FLOOR_FRACTION: f64 = 0.01;

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
    /// Requested outputs beyond the frames (not written by the run yet).
    pub outputs: Outputs,
    /// Things the user should know that are not errors (e.g. an output interval below
    /// the time step); `crash run` and `crash check` print them. A note that starts
    /// with `warning: ` reports something the run does differently from the input
    /// (e.g. friction ignored on request).
    pub notes: Vec<String>,
}

impl Built {
    /// The core driver's configuration for this scene (other fields default).
    pub fn run_config(&self) -> RunConfig {
        RunConfig {
            end_time: self.end_time,
            safety: self.safety,
            energy_limit: self.energy_limit,
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
        (Some(src), Some(el)) if src.written.is_some() => {
            // a keyword deck's element: point at its card
            let (file, line, tag) = src.element_origin(el).unwrap_or_default();
            SceneError {
                kind: ErrorKind::Geometry,
                file,
                line,
                column: 0,
                key: s.key.clone(),
                message: format!("*ELEMENT_SHELL {tag}: {e}"),
            }
        }
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

/// The section: thickness, material and the shear correction factor (default 5/6).
fn section(
    ctx: &Ctx,
    key: &str,
    b: &BodySpec,
    material: crash_core::Material,
) -> Result<Section, SceneError> {
    let mut sec = Section::new(material, b.thickness);
    if let Some(k) = b.shear_factor {
        if !(k.is_finite() && k > 0.0 && k <= 1.0) {
            return Err(ctx.invalid(
                &format!("{key}.shear_factor"),
                "must be in (0, 1] (transverse shear correction factor; 5/6 by default)",
            ));
        }
        sec.shear = k * material.shear_modulus() * b.thickness;
    }
    Ok(sec)
}

pub(crate) fn body(
    scene: &Scene,
    ctx: &Ctx,
    i: usize,
    b: &BodySpec,
    s: Shape,
    curves: &BTreeMap<String, Curve>,
) -> Result<(Body, BodyInfo, Option<Vec<u64>>), SceneError> {
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
    let section = section(ctx, &key, b, material)?;
    let local = s.mesh.nodes.clone();
    let rot = rotation(ctx, &format!("{key}.rotation"), b)?;
    let pos = finite_vec(ctx, &format!("{key}.position"), b.position)?;
    let mut mesh = s.mesh.clone();
    mesh.transform(&rot, pos);
    let mut body = Body::new(i as u32, &b.name, &mesh, section, Stabilization::default()).map_err(
        |e| match e {
            CoreError::Thickness { .. } => {
                ctx.invalid(&format!("{key}.thickness"), "must be finite and > 0 (m)")
            }
            CoreError::Material { field, valid, .. } => {
                ctx.invalid(&format!("materials.{}.{field}", b.material), valid)
            }
            other => geometry_error(ctx, &s, other),
        },
    )?;
    body.def_mut().mass_damping =
        non_negative(ctx, &format!("{key}.mass_damping"), b.mass_damping, "1/s")?;
    body.def_mut().contact = b.contact.unwrap_or(true);
    body.def_mut().self_contact = b.self_contact.unwrap_or(false);

    let v = finite_vec(ctx, &format!("{key}.velocity"), b.velocity)?;
    let w = finite_vec(ctx, &format!("{key}.angular_velocity"), b.angular_velocity)?;
    let centre = match b.angular_velocity_centre {
        Some(c) => finite_vec(ctx, &format!("{key}.angular_velocity_centre"), Some(c))?,
        None => body.centre_of_mass(),
    };
    body.set_rigid_velocity(v, w, centre);

    let global = body.def.x0.clone();
    let mut info = BodyInfo {
        shape: s.describe.clone(),
        material: b.material.clone(),
        fixed_nodes: 0,
        prescribed_nodes: 0,
        loaded_nodes: 0,
    };
    let tags = s.source.as_ref().map(|src| src.node_tags.clone());
    let element_tags: Option<Vec<u64>> = s
        .source
        .as_ref()
        .map(|src| src.element_tags.iter().map(|t| t.0).collect());
    let nodes = Nodes {
        local: &local,
        global: &global,
        tags: tags.as_deref(),
        element_tags: element_tags.as_deref(),
    };
    motion::apply(ctx, &key, b, &mut body, &nodes, curves, &mut info)?;
    info.fixed_nodes = body.def.fixed.iter().filter(|&&f| f != 0).count();
    info.prescribed_nodes = body
        .def
        .program
        .iter()
        .filter(|&&p| p != crash_core::body::NO_PROGRAM)
        .count();
    Ok((body, info, tags))
}

/// Refuse a scene whose meshes would not fit in the memory the machine has
/// (`available`: bytes, None when unknown), before any mesh is generated.
pub(crate) fn check_memory(
    ctx: &Ctx,
    plans: &[Planned],
    available: Option<u64>,
) -> Result<(), SceneError> {
    let Some(available) = available else {
        return Ok(());
    };
    let mut total = Counts::default();
    plans.iter().for_each(|p| total.add(p.counts));
    let need = total.bytes();
    if need <= available as f64 {
        return Ok(());
    }
    let largest = plans
        .iter()
        .max_by_key(|p| p.counts.elements())
        .map_or("bodies", |p| p.key.as_str());
    Err(ctx.key_error(
        ErrorKind::TooLarge,
        largest,
        format!(
            "the scene needs about {} of memory ({} elements, {} nodes; about {:.0} bytes per quad and its node, docs/scene-format.md \"Memory\"), more than the {} this machine has available (MemAvailable): coarsen the mesh or run on a larger machine",
            memory::human(need),
            total.elements(),
            total.nodes,
            Counts {
                nodes: 1,
                quads: 1,
                ..Counts::default()
            }
            .bytes(),
            memory::human(available as f64),
        ),
    ))
}

pub fn build(scene: &Scene, ctx: &Ctx, mut hash: Fnv) -> Result<Built, SceneError> {
    let g = &scene.globals;
    let mut plans = Vec::with_capacity(scene.spec.bodies.len());
    for (i, b) in scene.spec.bodies.iter().enumerate() {
        let mut p = plan(ctx, &scene.dir, i, b, &mut hash, &scene.inputs)?;
        if scene
            .materials
            .get(&b.material)
            .is_some_and(|m| m.kelvin > 0.0)
        {
            p.counts = p.counts.with_kelvin();
        }
        plans.push(p);
    }
    let available = scene.memory_limit.or_else(memory::available);
    check_memory(ctx, &plans, available)?;
    let curves = crate::curves::curves(ctx, &scene.spec)?;
    let mut bodies = Vec::with_capacity(scene.spec.bodies.len());
    let mut info = Vec::with_capacity(scene.spec.bodies.len());
    let mut tags = Vec::with_capacity(scene.spec.bodies.len());
    for (i, (b, p)) in scene.spec.bodies.iter().zip(plans).enumerate() {
        let (body, inf, t) = body(scene, ctx, i, b, p.generate(), &curves)?;
        bodies.push(body);
        info.push(inf);
        tags.push(t);
    }
    let ids: Vec<u32> = bodies.iter().map(|b| b.def.id).collect();
    let outputs = outputs::resolve(ctx, &scene.spec, &ids, &tags)?;
    let dt = bodies.iter().map(dt_estimate).fold(f64::INFINITY, f64::min);
    let (output_interval, notes) = output_interval(g, dt);
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
        output_interval,
        contact,
        margin_derived: !g.margin_given,
        energy_limit: g.energy_limit,
        scene_hash: hash.finish(),
        info,
        outputs,
        notes,
    })
}

/// The output interval to use given the smallest element time step estimate (no
/// safety factor): one below the time step means every step, with a note.
pub(crate) fn output_interval(g: &crate::globals::Globals, dt_estimate: f64) -> (f64, Vec<String>) {
    let dt = g.safety * dt_estimate;
    let mut notes = Vec::new();
    let mut output_interval = g.output_interval;
    if dt.is_finite() && output_interval < dt {
        notes.push(format!(
            "output_interval {output_interval:.3e} s is below the time step (about {dt:.3e} s): a frame is written every step"
        ));
        output_interval = output_interval.max(OUTPUT_FLOOR_FRACTION * dt);
    }
    (output_interval, notes)
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
            "bodies \"{}\" and \"{}\" interpenetrate at t = 0: {} {} of \"{}\" lie closer to \"{}\" than the half-thickness sum {:.4e} m ({} by {:.4e} m, at element {}); move them apart",
            a.name, b.name, p.nodes, p.at.counted(), a.name, b.name, gap, p.at, p.depth, p.segment
        ),
    )
}
