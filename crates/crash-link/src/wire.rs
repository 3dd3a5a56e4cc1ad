//! Commands and replies <-> generated wire messages, at the network edge. Bodies travel
//! as a state plus, when the receiver lacks it, a definition (crash-proto's body
//! conversions); the clock travels in Step and Load.

use crate::command::{BodyLoad, Command, GroupTime, Halo, Reply, Setup, StepReport};
use crash_core::contact::{ContactConfig, ContactPass, PenaltyKind, SegmentSides, SpeedRule};
use crash_core::partition::SplitFigures;
use crash_core::{Clock, Due, Vec3};
use crash_io::FrameBody;
use crash_proto::pb;
use crash_proto::pb::master_message::Command as PbCommand;
use crash_proto::pb::worker_message::Reply as PbReply;
use crash_proto::report::{
    contacts_from_pb, contacts_to_pb, fault_from_pb, fault_to_pb, probes_from_pb, probes_to_pb,
    reports_from_pb, reports_to_pb,
};
use crash_proto::{def_from_pb, def_to_pb, state_from_pb, state_to_pb, vec3_to_pb, ProtoError};

mod frames;
mod parts;

use parts::{
    part_bodies_from_pb, part_bodies_to_pb, part_dts_from_pb, part_dts_to_pb, part_states_from_pb,
    part_states_to_pb, spec_from_pb, spec_to_pb,
};
pub use parts::{peer_halo_from_pb, peer_halo_to_pb};

fn contact_to_pb(c: &ContactConfig) -> pb::ContactConfig {
    pb::ContactConfig {
        enabled: c.enabled,
        margin: c.margin,
        penalty_scale: c.penalty_scale,
        penalty: match c.penalty {
            PenaltyKind::Soft => "soft",
            PenaltyKind::Element => "element",
        }
        .into(),
        damping_ratio: c.damping_ratio,
        speed_rule: match c.speed_rule {
            SpeedRule::LimitDt => "limit_dt",
            SpeedRule::Stop => "stop",
        }
        .into(),
        pass: match c.pass {
            ContactPass::Nodes => "nodes",
            ContactPass::Segments => "segments",
        }
        .into(),
        sides: match c.sides {
            SegmentSides::Auto => "auto",
            SegmentSides::Finer => "finer",
            SegmentSides::Both => "both",
        }
        .into(),
    }
}

fn contact_from_pb(c: &pb::ContactConfig) -> Result<ContactConfig, ProtoError> {
    Ok(ContactConfig {
        enabled: c.enabled,
        margin: c.margin,
        penalty_scale: c.penalty_scale,
        penalty: match c.penalty.as_str() {
            "soft" => PenaltyKind::Soft,
            "element" => PenaltyKind::Element,
            other => {
                return Err(ProtoError::Invalid(format!(
                    "unknown penalty kind '{other}'"
                )))
            }
        },
        damping_ratio: c.damping_ratio,
        speed_rule: match c.speed_rule.as_str() {
            "" | "limit_dt" => SpeedRule::LimitDt,
            "stop" => SpeedRule::Stop,
            other => {
                return Err(ProtoError::Invalid(format!(
                    "unknown contact speed rule '{other}'"
                )))
            }
        },
        pass: match c.pass.as_str() {
            "" | "nodes" => ContactPass::Nodes,
            "segments" => ContactPass::Segments,
            other => {
                return Err(ProtoError::Invalid(format!(
                    "unknown contact pass '{other}'"
                )))
            }
        },
        sides: match c.sides.as_str() {
            "" | "auto" => SegmentSides::Auto,
            "finer" => SegmentSides::Finer,
            "both" => SegmentSides::Both,
            other => {
                return Err(ProtoError::Invalid(format!(
                    "unknown segment pass sides '{other}'"
                )))
            }
        },
    })
}

fn clock_to_pb(c: &Clock) -> pb::Clock {
    pb::Clock {
        step: c.step,
        time: c.time,
        last_dt: c.last_dt,
    }
}

fn clock_from_pb(c: Option<&pb::Clock>) -> Result<Clock, ProtoError> {
    let c = c.ok_or(ProtoError::Missing("clock"))?;
    Ok(Clock {
        step: c.step,
        time: c.time,
        last_dt: c.last_dt,
    })
}

/// A body load; `with_def`: send the definition if the load carries one.
pub fn load_to_pb(b: &BodyLoad, with_def: bool) -> pb::BodyLoad {
    pb::BodyLoad {
        def: b.def.as_ref().filter(|_| with_def).map(|d| def_to_pb(d)),
        state: Some(state_to_pb(b.id, &b.state)),
    }
}

pub fn load_from_pb(p: &pb::BodyLoad) -> Result<BodyLoad, ProtoError> {
    let s = p
        .state
        .as_ref()
        .ok_or(ProtoError::Missing("body_load.state"))?;
    let state = state_from_pb(s)?;
    let def = match &p.def {
        Some(d) => {
            if d.id != s.id {
                return Err(ProtoError::Invalid(format!(
                    "body definition {} carries the state of body {}",
                    d.id, s.id
                )));
            }
            Some(def_from_pb(d)?.def)
        }
        None => None,
    };
    Ok(BodyLoad {
        id: s.id,
        def,
        state,
    })
}

fn pack3(v: &[Vec3]) -> Vec<f64> {
    v.iter().flat_map(|p| [p.x, p.y, p.z]).collect()
}

fn unpack3(id: u32, field: &'static str, d: &[f64]) -> Result<Vec<Vec3>, ProtoError> {
    if !d.len().is_multiple_of(3) {
        return Err(ProtoError::Invalid(format!(
            "frame of body {id}: '{field}' is not whole triples"
        )));
    }
    Ok(d.chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect())
}

fn frame_body_to_pb(b: &FrameBody) -> pb::FrameBody {
    // whole arrays on the wire: the network worker completes a deferred capture on its
    // pool before this (crash-worker client.rs); a copy is completed here otherwise
    let b = &*b.completed();
    pb::FrameBody {
        id: b.id,
        name: b.name.clone(),
        thickness: b.thickness,
        x: pack3(&b.x),
        x0: pack3(&b.x0),
        v: pack3(&b.v),
        w: pack3(&b.w),
        tris: b.tris.iter().flatten().copied().collect(),
        quads: b.quads.iter().flatten().copied().collect(),
        von_mises_top: b.von_mises_top.clone(),
        von_mises_bottom: b.von_mises_bottom.clone(),
        n: b.n.iter().flatten().copied().collect(),
        m: b.m.iter().flatten().copied().collect(),
        f_contact: pack3(&b.f_contact),
    }
}

fn frame_body_from_pb(p: &pb::FrameBody) -> Result<FrameBody, ProtoError> {
    let id = p.id;
    let bad = |what: &str| ProtoError::Invalid(format!("frame of body {id}: {what}"));
    let x = unpack3(id, "x", &p.x)?;
    let nn = x.len() as u32;
    let x0 = unpack3(id, "x0", &p.x0)?;
    let v = unpack3(id, "v", &p.v)?;
    let w = unpack3(id, "w", &p.w)?;
    let f_contact = unpack3(id, "f_contact", &p.f_contact)?;
    if x0.len() != x.len() || v.len() != x.len() || w.len() != x.len() || f_contact.len() != x.len()
    {
        return Err(bad("nodal arrays differ in length"));
    }
    if !p.tris.len().is_multiple_of(3) || !p.quads.len().is_multiple_of(4) {
        return Err(bad("connectivity is not whole elements"));
    }
    if p.tris.iter().chain(&p.quads).any(|&n| n >= nn) {
        return Err(bad("connectivity names a node out of range"));
    }
    let ne = p.tris.len() / 3 + p.quads.len() / 4;
    if p.von_mises_top.len() != ne
        || p.von_mises_bottom.len() != ne
        || p.n.len() != 3 * ne
        || p.m.len() != 3 * ne
    {
        return Err(bad("element arrays do not match the elements"));
    }
    Ok(FrameBody {
        id,
        name: p.name.clone(),
        thickness: p.thickness,
        x,
        x0,
        v,
        w,
        tris: p.tris.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        quads: p
            .quads
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
        von_mises_top: p.von_mises_top.clone(),
        von_mises_bottom: p.von_mises_bottom.clone(),
        n: p.n.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        m: p.m.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        f_contact,
        placement: None,
        parts: None,
        pending: None,
    })
}

/// `flat` cut into runs of `sizes` (which must add up to its length).
pub(super) fn split_sizes(
    flat: &[u32],
    sizes: &[u32],
    what: &str,
) -> Result<Vec<Vec<u32>>, ProtoError> {
    let total: u64 = sizes.iter().map(|&s| s as u64).sum();
    if total != flat.len() as u64 {
        return Err(ProtoError::Invalid(format!(
            "regroup: group sizes add up to {total}, but {} {what} were sent",
            flat.len()
        )));
    }
    let mut out = Vec::with_capacity(sizes.len());
    let mut at = 0;
    for &s in sizes {
        out.push(flat[at..at + s as usize].to_vec());
        at += s as usize;
    }
    Ok(out)
}

fn wrap(c: PbCommand) -> pb::MasterMessage {
    pb::MasterMessage { command: Some(c) }
}

/// Encode a command. `has_def(id)`: the worker already holds that definition (a Load
/// then carries the state only).
pub fn command_to_pb(cmd: &Command, has_def: impl Fn(u32) -> bool) -> pb::MasterMessage {
    wrap(match cmd {
        Command::Setup(s) => PbCommand::Setup(pb::Setup {
            gravity: Some(vec3_to_pb(&s.gravity)),
            contact: Some(contact_to_pb(&s.contact)),
            reactions: s.reactions,
            probes: s.probes.iter().flat_map(|p| [p.0, p.1]).collect(),
        }),
        Command::Load { at, bodies } | Command::LoadCopies { at, bodies } => {
            PbCommand::Load(pb::Load {
                at: Some(clock_to_pb(at)),
                bodies: bodies
                    .iter()
                    .map(|b| load_to_pb(b, !has_def(b.id)))
                    .collect(),
                copies: matches!(cmd, Command::LoadCopies { .. }),
            })
        }
        Command::Unload { ids, with_def } | Command::Lend { ids, with_def } => {
            PbCommand::Unload(pb::Unload {
                ids: ids.clone(),
                with_def: with_def.clone(),
                keep: matches!(cmd, Command::Lend { .. }),
            })
        }
        Command::Regroup { groups, copies } => PbCommand::Regroup(pb::Regroup {
            members: groups.iter().flatten().copied().collect(),
            sizes: groups.iter().map(|g| g.len() as u32).collect(),
            copies: copies.iter().flatten().copied().collect(),
            copy_sizes: if copies.iter().all(Vec::is_empty) {
                Vec::new()
            } else {
                copies.iter().map(|g| g.len() as u32).collect()
            },
        }),
        Command::Start => PbCommand::Start(pb::Start {}),
        Command::Step {
            at,
            dt,
            kin_nodes,
            due,
            contact,
            direct,
        } => PbCommand::Step(pb::Step {
            at: Some(clock_to_pb(at)),
            dt: *dt,
            kin_nodes: *kin_nodes,
            reactions: due.reactions,
            probes: due.probes,
            contact: (!contact.is_empty()).then(|| part_dts_to_pb(contact)),
            direct: *direct,
        }),
        Command::Frame(ids) => PbCommand::Frame(pb::FrameRequest { ids: ids.clone() }),
        Command::States(ids) => PbCommand::States(pb::StatesRequest { ids: ids.clone() }),
        Command::Reset => PbCommand::Reset(pb::Reset {}),
        Command::Shutdown(reason) => PbCommand::Shutdown(pb::Shutdown {
            reason: reason.clone(),
        }),
        Command::Split(spec) => PbCommand::Split(spec_to_pb(spec)),
        Command::Share { at, spec, bodies } => PbCommand::Share(pb::Share {
            at: Some(clock_to_pb(at)),
            spec: Some(spec_to_pb(spec)),
            bodies: bodies
                .iter()
                .map(|b| load_to_pb(b, !has_def(b.id)))
                .collect(),
        }),
        Command::Halo(parts) => PbCommand::Halo(part_states_to_pb(parts)),
        Command::Contact(dts) => PbCommand::Contact(part_dts_to_pb(dts)),
        Command::Parts => PbCommand::Parts(pb::PartsRequest {}),
        Command::Assemble(parts) => PbCommand::Assemble(part_bodies_to_pb(parts)),
        Command::Unsplit => PbCommand::Unsplit(pb::Unsplit {}),
        Command::PartFrames(ids) => {
            PbCommand::PartFrames(pb::PartFramesRequest { ids: ids.clone() })
        }
    })
}

/// Decode a command on the worker. `Welcome` is part of the handshake, not a command.
pub fn command_from_pb(m: &pb::MasterMessage) -> Result<Command, ProtoError> {
    Ok(
        match m
            .command
            .as_ref()
            .ok_or(ProtoError::Missing("master_message.command"))?
        {
            PbCommand::Welcome(_) => {
                return Err(ProtoError::Invalid(
                    "a second Welcome in one session".into(),
                ))
            }
            PbCommand::Challenge(_) => {
                return Err(ProtoError::Invalid(
                    "a second Challenge in one session".into(),
                ))
            }
            PbCommand::Setup(s) => {
                let g = s
                    .gravity
                    .as_ref()
                    .ok_or(ProtoError::Missing("setup.gravity"))?;
                let c = s
                    .contact
                    .as_ref()
                    .ok_or(ProtoError::Missing("setup.contact"))?;
                if !s.probes.len().is_multiple_of(2) {
                    return Err(ProtoError::Invalid("setup: probes not in pairs".into()));
                }
                Command::Setup(Setup {
                    gravity: Vec3::new(g.x, g.y, g.z),
                    contact: contact_from_pb(c)?,
                    reactions: s.reactions,
                    probes: std::sync::Arc::new(
                        s.probes.chunks_exact(2).map(|p| (p[0], p[1])).collect(),
                    ),
                })
            }
            PbCommand::Load(l) => {
                let at = clock_from_pb(l.at.as_ref())?;
                let bodies = l
                    .bodies
                    .iter()
                    .map(load_from_pb)
                    .collect::<Result<_, _>>()?;
                if l.copies {
                    Command::LoadCopies { at, bodies }
                } else {
                    Command::Load { at, bodies }
                }
            }
            PbCommand::Unload(u) => {
                let (ids, with_def) = (u.ids.clone(), u.with_def.clone());
                if u.keep {
                    Command::Lend { ids, with_def }
                } else {
                    Command::Unload { ids, with_def }
                }
            }
            PbCommand::Regroup(r) => {
                let groups = split_sizes(&r.members, &r.sizes, "members")?;
                if !r.copy_sizes.is_empty() && r.copy_sizes.len() != r.sizes.len() {
                    return Err(ProtoError::Invalid(format!(
                        "regroup: {} groups but copies for {}",
                        r.sizes.len(),
                        r.copy_sizes.len()
                    )));
                }
                let copies = split_sizes(&r.copies, &r.copy_sizes, "copies")?;
                Command::Regroup { groups, copies }
            }
            PbCommand::Start(_) => Command::Start,
            PbCommand::Step(s) => Command::Step {
                at: clock_from_pb(s.at.as_ref())?,
                dt: s.dt,
                kin_nodes: s.kin_nodes,
                due: Due {
                    reactions: s.reactions,
                    probes: s.probes,
                },
                contact: match &s.contact {
                    Some(d) => part_dts_from_pb(d)?,
                    None => SplitFigures::default(),
                },
                direct: s.direct,
            },
            PbCommand::Frame(f) => Command::Frame(f.ids.clone()),
            PbCommand::States(s) => Command::States(s.ids.clone()),
            PbCommand::Reset(_) => Command::Reset,
            PbCommand::Shutdown(s) => Command::Shutdown(s.reason.clone()),
            PbCommand::Split(s) => Command::Split(spec_from_pb(Some(s))?),
            PbCommand::Share(s) => Command::Share {
                at: clock_from_pb(s.at.as_ref())?,
                spec: spec_from_pb(s.spec.as_ref())?,
                bodies: s
                    .bodies
                    .iter()
                    .map(load_from_pb)
                    .collect::<Result<_, _>>()?,
            },
            PbCommand::Halo(p) => Command::Halo(part_states_from_pb(Some(p))?),
            PbCommand::Contact(d) => Command::Contact(part_dts_from_pb(d)?),
            PbCommand::Parts(_) => Command::Parts,
            PbCommand::Assemble(p) => Command::Assemble(part_bodies_from_pb(p)?),
            PbCommand::Unsplit(_) => Command::Unsplit,
            PbCommand::PartFrames(f) => Command::PartFrames(f.ids.clone()),
        },
    )
}

/// Encode a worker's reply. Unloaded bodies carry a definition only where the master
/// asked for it (the engine leaves the others out).
fn report_to_pb(rep: &StepReport) -> pb::Report {
    pb::Report {
        bodies: Some(reports_to_pb(&rep.bodies)),
        group_first: rep.groups.iter().map(|g| g.first).collect(),
        group_nanos: rep.groups.iter().map(|g| g.nanos).collect(),
        compute_nanos: rep.compute_ns,
        contacts: Some(contacts_to_pb(&rep.contacts)),
        codec_nanos: rep.codec_ns,
        probes: (!rep.probes.is_empty()).then(|| probes_to_pb(&rep.probes)),
        parts: (!rep.parts.is_empty()).then(|| part_states_to_pb(&rep.parts)),
        part_dts: (!rep.part_dts.is_empty()).then(|| part_dts_to_pb(&rep.part_dts)),
        split_contacts: (!rep.split_contacts.is_empty())
            .then(|| contacts_to_pb(&rep.split_contacts)),
        limit_ids: rep.split_limits.iter().map(|l| l.0).collect(),
        limit_dts: rep.split_limits.iter().map(|l| l.1).collect(),
        halo: rep.halo.as_deref().map(|h| {
            Box::new(pb::Halo {
                outcome: Some(match h {
                    Halo::Report(r) => pb::halo::Outcome::Report(Box::new(report_to_pb(r))),
                    Halo::Fault {
                        group_first,
                        fault,
                        split_contacts,
                    } => pb::halo::Outcome::Failure(fault_failure(
                        *group_first,
                        fault,
                        split_contacts.as_deref(),
                    )),
                    Halo::Error(e) => pb::halo::Outcome::Failure(error_failure(e)),
                    Halo::Lost(e) => pb::halo::Outcome::Lost(e.clone()),
                }),
            })
        }),
    }
}

fn fault_failure(
    group_first: u32,
    fault: &crash_core::Fault,
    split_contacts: Option<&[crash_core::contact::PairStats]>,
) -> pb::Failure {
    pb::Failure {
        kind: Some(pb::failure::Kind::Fault(fault_to_pb(fault))),
        group_first,
        split_contacts: split_contacts.map(contacts_to_pb),
    }
}

fn error_failure(e: &str) -> pb::Failure {
    pb::Failure {
        kind: Some(pb::failure::Kind::Error(e.to_string())),
        group_first: 0,
        split_contacts: None,
    }
}

pub fn reply_to_pb(r: &Reply) -> pb::WorkerMessage {
    let reply = match r {
        Reply::Ack => PbReply::Ack(pb::Ack {}),
        Reply::Report(rep) => PbReply::Report(report_to_pb(rep)),
        Reply::Parts(p) => PbReply::Parts(part_bodies_to_pb(p)),
        Reply::Unloaded(bodies) => PbReply::Unloaded(pb::BodyLoads {
            bodies: bodies.iter().map(|b| load_to_pb(b, true)).collect(),
        }),
        Reply::Frame(bodies) => PbReply::Frame(pb::Frame {
            bodies: bodies.iter().map(frame_body_to_pb).collect(),
        }),
        Reply::PartFrames(parts) => PbReply::PartFrames(pb::PartFrames {
            parts: parts.iter().map(frames::part_frame_to_pb).collect(),
        }),
        Reply::States(states) => PbReply::States(pb::States {
            states: states.iter().map(|(id, s)| state_to_pb(*id, s)).collect(),
        }),
        Reply::Fault {
            group_first,
            fault,
            split_contacts,
        } => PbReply::Failure(fault_failure(
            *group_first,
            fault,
            split_contacts.as_deref(),
        )),
        Reply::Error(e) => PbReply::Failure(error_failure(e)),
    };
    pb::WorkerMessage { reply: Some(reply) }
}

/// Decode a worker's reply on the master. `Hello` belongs to the handshake.
pub fn reply_from_pb(msg: &pb::WorkerMessage) -> Result<Reply, ProtoError> {
    Ok(
        match msg
            .reply
            .as_ref()
            .ok_or(ProtoError::Missing("worker_message.reply"))?
        {
            PbReply::Ack(_) => Reply::Ack,
            PbReply::Report(r) => Reply::Report(report_from_pb(r)?),
            PbReply::Unloaded(b) => Reply::Unloaded(
                b.bodies
                    .iter()
                    .map(load_from_pb)
                    .collect::<Result<_, _>>()?,
            ),
            PbReply::Frame(f) => Reply::Frame(
                f.bodies
                    .iter()
                    .map(frame_body_from_pb)
                    .collect::<Result<_, _>>()?,
            ),
            PbReply::States(s) => Reply::States(
                s.states
                    .iter()
                    .map(|p| Ok((p.id, state_from_pb(p)?)))
                    .collect::<Result<_, ProtoError>>()?,
            ),
            PbReply::Failure(f) => failure_from_pb(f)?,
            PbReply::Parts(p) => Reply::Parts(part_bodies_from_pb(p)?),
            PbReply::PartFrames(f) => Reply::PartFrames(
                f.parts
                    .iter()
                    .map(frames::part_frame_from_pb)
                    .collect::<Result<_, _>>()?,
            ),
            PbReply::Hello(_) => return Err(ProtoError::Invalid("a second Hello".into())),
        },
    )
}

fn failure_from_pb(f: &pb::Failure) -> Result<Reply, ProtoError> {
    Ok(
        match f.kind.as_ref().ok_or(ProtoError::Missing("failure.kind"))? {
            pb::failure::Kind::Fault(fault) => Reply::Fault {
                group_first: f.group_first,
                fault: fault_from_pb(fault)?,
                split_contacts: f
                    .split_contacts
                    .as_ref()
                    .map(contacts_from_pb)
                    .transpose()?,
            },
            pb::failure::Kind::Error(e) => Reply::Error(e.clone()),
        },
    )
}

fn halo_from_pb(h: &pb::Halo) -> Result<Halo, ProtoError> {
    Ok(
        match h
            .outcome
            .as_ref()
            .ok_or(ProtoError::Missing("halo.outcome"))?
        {
            pb::halo::Outcome::Report(r) => Halo::Report(Box::new(report_from_pb(r)?)),
            pb::halo::Outcome::Failure(f) => Halo::from_reply(failure_from_pb(f)?),
            pb::halo::Outcome::Lost(e) => Halo::Lost(e.clone()),
        },
    )
}

/// Decode a step report.
pub fn report_from_pb(r: &pb::Report) -> Result<StepReport, ProtoError> {
    if r.group_first.len() != r.group_nanos.len() {
        return Err(ProtoError::Invalid(
            "report: group columns differ in length".into(),
        ));
    }
    Ok(StepReport {
        bodies: reports_from_pb(
            r.bodies
                .as_ref()
                .ok_or(ProtoError::Missing("report.bodies"))?,
        )?,
        groups: r
            .group_first
            .iter()
            .zip(&r.group_nanos)
            .map(|(&first, &nanos)| GroupTime { first, nanos })
            .collect(),
        compute_ns: r.compute_nanos,
        contacts: match &r.contacts {
            Some(c) => contacts_from_pb(c)?,
            None => Vec::new(),
        },
        codec_ns: r.codec_nanos,
        probes: match &r.probes {
            Some(p) => probes_from_pb(p)?,
            None => Vec::new(),
        },
        parts: part_states_from_pb(r.parts.as_ref())?,
        part_dts: match &r.part_dts {
            Some(d) => part_dts_from_pb(d)?,
            None => SplitFigures::default(),
        },
        split_contacts: match &r.split_contacts {
            Some(c) => contacts_from_pb(c)?,
            None => Vec::new(),
        },
        split_limits: {
            if r.limit_ids.len() != r.limit_dts.len() {
                return Err(ProtoError::Invalid(format!(
                    "report.limit_ids has {} entries, report.limit_dts {}",
                    r.limit_ids.len(),
                    r.limit_dts.len()
                )));
            }
            r.limit_ids
                .iter()
                .copied()
                .zip(r.limit_dts.iter().copied())
                .collect()
        },
        halo: r
            .halo
            .as_deref()
            .map(halo_from_pb)
            .transpose()?
            .map(Box::new),
    })
}
