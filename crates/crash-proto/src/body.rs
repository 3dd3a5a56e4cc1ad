//! Body <-> (BodyDef, BodyState): all the state needed to continue a body bit for bit,
//! as packed repeated doubles with fixed strides (see proto/crash/v1/body.proto).
//!
//! Decoding rebuilds the body with `Body::new` from the reference mesh (so that fields
//! this crate does not know about get their constructor values) and then overwrites
//! every field the wire carries with the exact transmitted bits; the round-trip test
//! compares the complete serialized body, so a field added to `Body` and not carried
//! here makes it fail.

use crate::error::ProtoError;
use crate::pb;
use crash_core::body::NodalLoad;
use crash_core::element::{HourglassState, ShellState, Stabilization};
use crash_core::{
    Body, BodyDef, BodyEnergy, BodyState, Material, Mesh, Section, TimeCurve, Vec3,
    VelocityProgram, NO_CURVE,
};

const TRI_REF: usize = 7;
const QUAD_REF: usize = 11;
/// velocity[3], angular[3], ramp, kind (0 velocity, 1 displacement).
const PROGRAM: usize = 8;
const LOAD: usize = 8;

pub(crate) fn pack3(v: &[Vec3]) -> Vec<f64> {
    let mut out = Vec::with_capacity(3 * v.len());
    for p in v {
        out.extend_from_slice(&[p.x, p.y, p.z]);
    }
    out
}

pub(crate) fn vec3(d: &[f64]) -> Vec3 {
    Vec3::new(d[0], d[1], d[2])
}

/// Check that `data` has `count * stride` values.
fn check<T>(
    body: u32,
    field: &'static str,
    data: &[T],
    count: usize,
    stride: usize,
) -> Result<(), ProtoError> {
    if data.len() != count * stride {
        return Err(ProtoError::Length {
            body,
            field,
            got: data.len(),
            expected: count * stride,
        });
    }
    Ok(())
}

fn unpack3(body: u32, field: &'static str, d: &[f64], n: usize) -> Result<Vec<Vec3>, ProtoError> {
    check(body, field, d, n, 3)?;
    Ok(d.chunks_exact(3).map(vec3).collect())
}

fn energy_to_pb(e: &BodyEnergy) -> pb::Energy {
    pb::Energy {
        kinetic: e.kinetic,
        internal: e.internal,
        hourglass: e.hourglass,
        contact: e.contact,
        damping: e.damping,
        external: e.external,
    }
}

pub(crate) fn energy_from_pb(e: &pb::Energy) -> BodyEnergy {
    BodyEnergy {
        kinetic: e.kinetic,
        internal: e.internal,
        hourglass: e.hourglass,
        contact: e.contact,
        damping: e.damping,
        external: e.external,
    }
}

/// The static part of a body.
pub fn def_to_pb(b: &BodyDef) -> pb::BodyDef {
    let s = &b.section;
    let m = &s.material;
    let mut tri_nodes = Vec::with_capacity(3 * b.tris.len());
    let mut tri_ref = Vec::with_capacity(TRI_REF * b.tris.len());
    for e in &b.tris {
        tri_nodes.extend_from_slice(&e.nodes);
        tri_ref.extend_from_slice(&e.bx0);
        tri_ref.extend_from_slice(&e.by0);
        tri_ref.push(e.area0);
    }
    let mut quad_nodes = Vec::with_capacity(4 * b.quads.len());
    let mut quad_ref = Vec::with_capacity(QUAD_REF * b.quads.len());
    for e in &b.quads {
        quad_nodes.extend_from_slice(&e.nodes);
        quad_ref.extend_from_slice(&e.bx0);
        quad_ref.extend_from_slice(&e.by0);
        quad_ref.extend_from_slice(&[e.hx, e.hy, e.area0]);
        quad_ref.extend_from_slice(&e.e0);
        quad_ref.push(e.bb);
    }
    let mut programs = Vec::with_capacity(PROGRAM * b.programs.len());
    for p in &b.programs {
        programs.extend_from_slice(&[p.velocity.x, p.velocity.y, p.velocity.z]);
        programs.extend_from_slice(&[p.angular.x, p.angular.y, p.angular.z]);
        programs.push(p.ramp);
        programs.push(if p.displacement { 1.0 } else { 0.0 });
    }
    let mut load_values = Vec::with_capacity(LOAD * b.loads.len());
    for l in &b.loads {
        load_values.extend_from_slice(&[l.force.x, l.force.y, l.force.z]);
        load_values.extend_from_slice(&[l.moment.x, l.moment.y, l.moment.z, l.t0, l.t1]);
    }
    pb::BodyDef {
        id: b.id,
        name: b.name.clone(),
        section: Some(pb::Section {
            material: Some(pb::Material {
                density: m.density,
                young: m.young,
                poisson: m.poisson,
                kelvin: m.kelvin,
            }),
            thickness: s.thickness,
            membrane: s.membrane,
            bending: s.bending,
            shear: s.shear,
            wave_speed: s.wave_speed,
        }),
        stab: Some(pb::Stabilization {
            hourglass_membrane: b.stab.hourglass_membrane,
            hourglass_w: b.stab.hourglass_w,
            hourglass_rotation: b.stab.hourglass_rotation,
            drilling: b.stab.drilling,
        }),
        x0: pack3(&b.x0),
        tri_nodes,
        tri_ref,
        quad_nodes,
        quad_ref,
        mass: b.mass.clone(),
        inertia: b.inertia.clone(),
        fixed: b.fixed.clone(),
        program: b.program.iter().map(|&p| p as u32).collect(),
        programs,
        load_nodes: b.loads.iter().map(|l| l.node).collect(),
        load_values,
        load_of: b.load_of.clone(),
        gather_start: b.gather_start.clone(),
        gather_slot: b.gather_slot.clone(),
        mass_damping: b.mass_damping,
        contact: b.contact,
        self_contact: b.self_contact,
        kinematic: b.kinematic,
        program_curve: b.programs.iter().map(|p| p.curve).collect(),
        load_curve: b.loads.iter().map(|l| l.curve).collect(),
        curve_len: b.curves.iter().map(|c| c.points.len() as u32).collect(),
        curve_points: b
            .curves
            .iter()
            .flat_map(|c| c.points.iter().flat_map(|p| [p.0, p.1]))
            .collect(),
    }
}

/// The evolving part of a body: a settled state (`Body::settled_state`; node sums, which
/// are not carried, would leave the slots stale).
pub fn state_to_pb(id: u32, b: &BodyState) -> pb::BodyState {
    let mut shell = Vec::with_capacity(6 * b.shell.len());
    for s in &b.shell {
        shell.extend_from_slice(&s.m);
        shell.extend_from_slice(&s.q);
        shell.push(s.drill);
    }
    let mut hourglass = Vec::with_capacity(3 * b.hourglass.len());
    for h in &b.hourglass {
        hourglass.push(h.w);
        hourglass.extend_from_slice(&h.th);
    }
    pb::BodyState {
        id,
        x: pack3(&b.x),
        v: pack3(&b.v),
        w: pack3(&b.w),
        shell,
        hourglass,
        slots: b.slots.iter().flatten().copied().collect(),
        f_contact: pack3(&b.f_contact),
        energy: Some(energy_to_pb(&b.energy)),
        internal_now: b.internal_now,
        hourglass_now: b.hourglass_now,
    }
}

pub fn body_to_pb(b: &Body) -> pb::Body {
    pb::Body {
        def: Some(def_to_pb(&b.def)),
        // forces carried as node sums go in the slots (crash_core::summed)
        state: Some(state_to_pb(b.def.id, &b.settled_state())),
    }
}

fn section_from_pb(s: &pb::Section) -> Result<Section, ProtoError> {
    let m = s
        .material
        .as_ref()
        .ok_or(ProtoError::Missing("section.material"))?;
    let material = Material::new(m.density, m.young, m.poisson, m.kelvin)?;
    let mut section = Section::new(material, s.thickness);
    section.membrane = s.membrane;
    section.bending = s.bending;
    section.shear = s.shear;
    section.wave_speed = s.wave_speed;
    Ok(section)
}

fn stab_from_pb(s: &pb::Stabilization) -> Stabilization {
    Stabilization {
        hourglass_membrane: s.hourglass_membrane,
        hourglass_w: s.hourglass_w,
        hourglass_rotation: s.hourglass_rotation,
        drilling: s.drilling,
    }
}

/// Rebuild a body from its definition and state.
pub fn body_from_pb(p: &pb::Body) -> Result<Body, ProtoError> {
    let d = p.def.as_ref().ok_or(ProtoError::Missing("body.def"))?;
    let st = p.state.as_ref().ok_or(ProtoError::Missing("body.state"))?;
    if st.id != d.id {
        return Err(ProtoError::Invalid(format!(
            "body definition {} carries the state of body {}",
            d.id, st.id
        )));
    }
    let mut b = def_from_pb(d)?;
    apply_state(&mut b, st)?;
    Ok(b)
}

/// Rebuild a body from its definition alone: the state is the one `Body::new` gives
/// (initial positions, at rest); apply a transmitted state with `apply_state`.
pub fn def_from_pb(d: &pb::BodyDef) -> Result<Body, ProtoError> {
    let id = d.id;
    let section = section_from_pb(
        d.section
            .as_ref()
            .ok_or(ProtoError::Missing("body.section"))?,
    )?;
    let stab = stab_from_pb(d.stab.as_ref().ok_or(ProtoError::Missing("body.stab"))?);
    if !d.x0.len().is_multiple_of(3)
        || !d.tri_nodes.len().is_multiple_of(3)
        || !d.quad_nodes.len().is_multiple_of(4)
    {
        return Err(ProtoError::Invalid(format!(
            "body {id}: node or connectivity arrays are not whole triples/quadruples"
        )));
    }
    let nn = d.x0.len() / 3;
    let mesh = Mesh {
        nodes: unpack3(id, "x0", &d.x0, nn)?,
        tris: d
            .tri_nodes
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
        quads: (d.quad_nodes.chunks_exact(4))
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
    };
    let mut b = Body::new(id, &d.name, &mesh, section, stab)?;
    let (nt, nq) = (b.def.tris.len(), b.def.quads.len());

    check(id, "tri_ref", &d.tri_ref, nt, TRI_REF)?;
    for (e, r) in b
        .def_mut()
        .tris
        .iter_mut()
        .zip(d.tri_ref.chunks_exact(TRI_REF))
    {
        e.bx0.copy_from_slice(&r[0..3]);
        e.by0.copy_from_slice(&r[3..6]);
        e.area0 = r[6];
    }
    check(id, "quad_ref", &d.quad_ref, nq, QUAD_REF)?;
    for (e, r) in b
        .def_mut()
        .quads
        .iter_mut()
        .zip(d.quad_ref.chunks_exact(QUAD_REF))
    {
        e.bx0.copy_from_slice(&r[0..2]);
        e.by0.copy_from_slice(&r[2..4]);
        (e.hx, e.hy, e.area0) = (r[4], r[5], r[6]);
        e.e0.copy_from_slice(&r[7..10]);
        e.bb = r[10];
    }
    check(id, "mass", &d.mass, nn, 1)?;
    check(id, "inertia", &d.inertia, nn, 1)?;
    check(id, "fixed", &d.fixed, nn, 1)?;
    check(id, "program", &d.program, nn, 1)?;
    check(id, "load_of", &d.load_of, nn, 1)?;
    check(
        id,
        "gather_start",
        &d.gather_start,
        b.def.gather_start.len(),
        1,
    )?;
    check(
        id,
        "gather_slot",
        &d.gather_slot,
        b.def.gather_slot.len(),
        1,
    )?;
    if !d.programs.len().is_multiple_of(PROGRAM) {
        return Err(ProtoError::Invalid(format!(
            "body {id}: programs not whole"
        )));
    }
    check(id, "load_values", &d.load_values, d.load_nodes.len(), LOAD)?;
    check(
        id,
        "program_curve",
        &d.program_curve,
        d.programs.len() / PROGRAM,
        1,
    )?;
    check(id, "load_curve", &d.load_curve, d.load_nodes.len(), 1)?;
    let points: u64 = d.curve_len.iter().map(|&n| n as u64).sum();
    if points.checked_mul(2) != Some(d.curve_points.len() as u64) {
        return Err(ProtoError::Invalid(format!(
            "body {id}: curves of {points} points carry {} values",
            d.curve_points.len()
        )));
    }
    let mut at = 0;
    let mut curves = Vec::with_capacity(d.curve_len.len());
    for &n in &d.curve_len {
        let v = &d.curve_points[at..at + 2 * n as usize];
        at += 2 * n as usize;
        let c = TimeCurve {
            points: v.chunks_exact(2).map(|p| (p[0], p[1])).collect(),
        };
        if !c.is_valid() {
            return Err(ProtoError::Invalid(format!(
                "body {id}: a load curve is not a time table"
            )));
        }
        curves.push(c);
    }
    b.def_mut().curves = curves;
    b.def_mut().mass.clone_from(&d.mass);
    b.def_mut().inertia.clone_from(&d.inertia);
    b.def_mut().fixed.clone_from(&d.fixed);
    b.def_mut().program = d
        .program
        .iter()
        .map(|&p| {
            u16::try_from(p).map_err(|_| ProtoError::Invalid(format!("body {id}: program {p}")))
        })
        .collect::<Result<_, _>>()?;
    b.def_mut().programs = d
        .programs
        .chunks_exact(PROGRAM)
        .zip(&d.program_curve)
        .map(|(c, &curve)| {
            let displacement = match c[7] {
                0.0 => false,
                1.0 => true,
                k => {
                    return Err(ProtoError::Invalid(format!(
                        "body {id}: program kind {k} (0: velocity, 1: displacement)"
                    )))
                }
            };
            Ok(VelocityProgram {
                velocity: vec3(&c[0..3]),
                angular: vec3(&c[3..6]),
                ramp: c[6],
                curve,
                displacement,
            })
        })
        .collect::<Result<_, _>>()?;
    b.def_mut().loads = d
        .load_nodes
        .iter()
        .zip(d.load_values.chunks_exact(LOAD))
        .zip(&d.load_curve)
        .map(|((&node, c), &curve)| NodalLoad {
            node,
            force: vec3(&c[0..3]),
            moment: vec3(&c[3..6]),
            t0: c[6],
            t1: c[7],
            curve,
        })
        .collect();
    b.def_mut().load_of.clone_from(&d.load_of);
    b.def_mut().gather_start.clone_from(&d.gather_start);
    b.def_mut().gather_slot.clone_from(&d.gather_slot);
    b.def_mut().mass_damping = d.mass_damping;
    b.def_mut().contact = d.contact;
    b.def_mut().self_contact = d.self_contact;
    b.def_mut().kinematic = d.kinematic;
    validate_indices(&b)?;
    Ok(b)
}

/// Indices that the physics uses to index arrays must be in range (a corrupt message
/// must not make a worker panic).
fn validate_indices(b: &Body) -> Result<(), ProtoError> {
    let id = b.def.id;
    let bad = |what: String| Err(ProtoError::Invalid(format!("body {id}: {what}")));
    let np = b.def.programs.len();
    if let Some(p) = b
        .def
        .program
        .iter()
        .find(|&&p| p != crash_core::body::NO_PROGRAM && p as usize >= np)
    {
        return bad(format!("velocity program {p} of {np}"));
    }
    let nl = b.def.loads.len();
    if let Some(l) = b
        .def
        .load_of
        .iter()
        .find(|&&l| l != u32::MAX && l as usize >= nl)
    {
        return bad(format!("load {l} of {nl}"));
    }
    let nc = b.def.curves.len();
    let curves = b.def.programs.iter().map(|p| p.curve);
    if let Some(c) = curves
        .chain(b.def.loads.iter().map(|l| l.curve))
        .find(|&c| c != NO_CURVE && c as usize >= nc)
    {
        return bad(format!("load curve {c} of {nc}"));
    }
    let nn = b.def.x0.len();
    if let Some(l) = b.def.loads.iter().find(|l| l.node as usize >= nn) {
        return bad(format!("load on node {} of {nn}", l.node));
    }
    let ns = b.state.slots.len() as u32;
    if b.def.gather_slot.iter().any(|&s| s >= ns)
        || b.def
            .gather_start
            .iter()
            .any(|&s| s as usize > b.def.gather_slot.len())
        || b.def.gather_start.windows(2).any(|w| w[0] > w[1])
    {
        return bad("gather map out of range".into());
    }
    Ok(())
}

/// Decode a state on its own (strides checked; whether it fits a definition is checked
/// when the two are joined, `Body::from_parts`).
pub fn state_from_pb(s: &pb::BodyState) -> Result<BodyState, ProtoError> {
    let id = s.id;
    let whole = |field: &'static str, d: &[f64], stride: usize| -> Result<usize, ProtoError> {
        if d.len().is_multiple_of(stride) {
            Ok(d.len() / stride)
        } else {
            Err(ProtoError::Invalid(format!(
                "body {id}: '{field}' has {} values, not a multiple of {stride}",
                d.len()
            )))
        }
    };
    let nn = whole("x", &s.x, 3)?;
    let x = unpack3(id, "x", &s.x, nn)?;
    let v = unpack3(id, "v", &s.v, nn)?;
    let w = unpack3(id, "w", &s.w, nn)?;
    whole("shell", &s.shell, 6)?;
    whole("hourglass", &s.hourglass, 3)?;
    whole("slots", &s.slots, 6)?;
    whole("f_contact", &s.f_contact, 3)?;
    let energy = s
        .energy
        .as_ref()
        .ok_or(ProtoError::Missing("state.energy"))?;
    Ok(BodyState {
        x,
        v,
        w,
        shell: s
            .shell
            .chunks_exact(6)
            .map(|c| ShellState {
                m: [c[0], c[1], c[2]],
                q: [c[3], c[4]],
                drill: c[5],
            })
            .collect(),
        hourglass: s
            .hourglass
            .chunks_exact(3)
            .map(|c| HourglassState {
                w: c[0],
                th: [c[1], c[2]],
            })
            .collect(),
        slots: s
            .slots
            .chunks_exact(6)
            .map(|c| [c[0], c[1], c[2], c[3], c[4], c[5]])
            .collect(),
        node_sums: Vec::new(),
        f_contact: s.f_contact.chunks_exact(3).map(vec3).collect(),
        energy: energy_from_pb(energy),
        internal_now: s.internal_now,
        hourglass_now: s.hourglass_now,
    })
}

/// Overwrite the evolving state of `b` with `s` (exact bits). The sizes must match the
/// body's definition.
pub fn apply_state(b: &mut Body, s: &pb::BodyState) -> Result<(), ProtoError> {
    let id = b.def.id;
    if s.id != id {
        return Err(ProtoError::Invalid(format!(
            "state of body {} applied to body {id}",
            s.id
        )));
    }
    let nn = b.state.x.len();
    let ne = b.state.shell.len();
    let nq = b.state.hourglass.len();
    let nslot = b.state.slots.len();
    let x = unpack3(id, "x", &s.x, nn)?;
    let v = unpack3(id, "v", &s.v, nn)?;
    let w = unpack3(id, "w", &s.w, nn)?;
    check(id, "shell", &s.shell, ne, 6)?;
    check(id, "hourglass", &s.hourglass, nq, 3)?;
    check(id, "slots", &s.slots, nslot, 6)?;
    if !(s.f_contact.is_empty() || s.f_contact.len() == 3 * nn) {
        check(id, "f_contact", &s.f_contact, nn, 3)?;
    }
    let energy = s
        .energy
        .as_ref()
        .ok_or(ProtoError::Missing("state.energy"))?;
    b.state.x = x;
    b.state.v = v;
    b.state.w = w;
    for (st, c) in b.state.shell.iter_mut().zip(s.shell.chunks_exact(6)) {
        st.m = [c[0], c[1], c[2]];
        st.q = [c[3], c[4]];
        st.drill = c[5];
    }
    for (h, c) in b
        .state
        .hourglass
        .iter_mut()
        .zip(s.hourglass.chunks_exact(3))
    {
        h.w = c[0];
        h.th = [c[1], c[2]];
    }
    for (slot, c) in b.state.slots.iter_mut().zip(s.slots.chunks_exact(6)) {
        slot.copy_from_slice(c);
    }
    b.state.node_sums.clear();
    b.state.f_contact = s.f_contact.chunks_exact(3).map(vec3).collect();
    b.state.energy = energy_from_pb(energy);
    b.state.internal_now = s.internal_now;
    b.state.hourglass_now = s.hourglass_now;
    Ok(())
}
