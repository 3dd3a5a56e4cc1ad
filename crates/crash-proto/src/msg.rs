//! The domain form of the master <-> worker protocol and its wire conversions.
//!
//! In local mode these values move between the master loop and in-process workers
//! without any serialization; over gRPC they are converted here, at the edge.

use crate::body::{body_from_pb, body_to_pb, state_to_pb};
use crate::error::ProtoError;
use crate::pb;
use crate::pb::master_message::Command as PbCommand;
use crate::pb::worker_message::Reply as PbReply;
use crate::report::{contacts_from_pb, contacts_to_pb, fault_to_pb, reports_to_pb};
use crash_core::contact::{ContactConfig, PairStats, PenaltyKind};
use crash_core::{Body, BodyReport, Fault, Vec3};

/// Run-wide parameters every group needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    pub gravity: Vec3,
    pub contact: ContactConfig,
}

/// What the master tells a worker. Every command gets exactly one [`Reply`].
#[derive(Debug, Clone)]
pub enum Command {
    Setup(Setup),
    /// Take these bodies (whole state).
    Load(Vec<Body>),
    /// Give these bodies back and forget them.
    Unload(Vec<u32>),
    /// The groups the worker integrates from now on (each sorted by id, the groups by
    /// their smallest id); every body held appears exactly once.
    Regroup(Vec<Vec<u32>>),
    /// Forces of the initial configuration.
    Start,
    /// Take step `step` (the step counter before it) of length `dt`.
    Step {
        step: u64,
        dt: f64,
    },
    /// Copies of every body held.
    Snapshot,
    Shutdown(String),
}

/// Compute time of one group in one step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GroupTime {
    /// Smallest body id of the group.
    pub first: u32,
    pub nanos: u64,
}

/// A worker's answer to Start or Step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepReport {
    pub bodies: Vec<BodyReport>,
    pub groups: Vec<GroupTime>,
    /// Wall time the worker spent on the command.
    pub compute_ns: u64,
    /// Contact statistics of the worker's groups, group after group.
    pub contacts: Vec<PairStats>,
}

#[derive(Debug, Clone)]
pub enum Reply {
    Ack,
    Report(StepReport),
    Unloaded(Vec<Body>),
    Snapshot(Vec<Body>),
    /// A physical fault in the group whose smallest body id is `group_first`.
    Fault {
        group_first: u32,
        fault: Fault,
    },
    /// The command could not be carried out (a protocol or bookkeeping error).
    Error(String),
}

pub fn vec3_to_pb(v: &Vec3) -> pb::Vec3 {
    pb::Vec3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

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
    })
}

fn wrap(c: PbCommand) -> pb::MasterMessage {
    pb::MasterMessage { command: Some(c) }
}

/// Encode a command (bodies by reference: the caller keeps them).
pub fn command_to_pb(cmd: &Command) -> pb::MasterMessage {
    wrap(match cmd {
        Command::Setup(s) => PbCommand::Setup(pb::Setup {
            gravity: Some(vec3_to_pb(&s.gravity)),
            contact: Some(contact_to_pb(&s.contact)),
        }),
        Command::Load(bodies) => PbCommand::Load(pb::Load {
            bodies: bodies.iter().map(body_to_pb).collect(),
        }),
        Command::Unload(ids) => PbCommand::Unload(pb::Unload { ids: ids.clone() }),
        Command::Regroup(groups) => PbCommand::Regroup(pb::Regroup {
            members: groups.iter().flatten().copied().collect(),
            sizes: groups.iter().map(|g| g.len() as u32).collect(),
        }),
        Command::Start => PbCommand::Start(pb::Start {}),
        Command::Step { step, dt } => PbCommand::Step(pb::Step {
            step: *step,
            dt: *dt,
        }),
        Command::Snapshot => PbCommand::Snapshot(pb::SnapshotRequest {}),
        Command::Shutdown(reason) => PbCommand::Shutdown(pb::Shutdown {
            reason: reason.clone(),
        }),
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
            PbCommand::Setup(s) => {
                let g = s
                    .gravity
                    .as_ref()
                    .ok_or(ProtoError::Missing("setup.gravity"))?;
                let c = s
                    .contact
                    .as_ref()
                    .ok_or(ProtoError::Missing("setup.contact"))?;
                Command::Setup(Setup {
                    gravity: Vec3::new(g.x, g.y, g.z),
                    contact: contact_from_pb(c)?,
                })
            }
            PbCommand::Load(l) => Command::Load(
                l.bodies
                    .iter()
                    .map(body_from_pb)
                    .collect::<Result<_, _>>()?,
            ),
            PbCommand::Unload(u) => Command::Unload(u.ids.clone()),
            PbCommand::Regroup(r) => {
                let total: u64 = r.sizes.iter().map(|&s| s as u64).sum();
                if total != r.members.len() as u64 {
                    return Err(ProtoError::Invalid(format!(
                        "regroup: group sizes add up to {total}, but {} members were sent",
                        r.members.len()
                    )));
                }
                let mut groups = Vec::with_capacity(r.sizes.len());
                let mut at = 0;
                for &s in &r.sizes {
                    groups.push(r.members[at..at + s as usize].to_vec());
                    at += s as usize;
                }
                Command::Regroup(groups)
            }
            PbCommand::Start(_) => Command::Start,
            PbCommand::Step(s) => Command::Step {
                step: s.step,
                dt: s.dt,
            },
            PbCommand::Snapshot(_) => Command::Snapshot,
            PbCommand::Shutdown(s) => Command::Shutdown(s.reason.clone()),
        },
    )
}

/// Encode a worker's reply. Unloaded and snapshot bodies travel as states only: the
/// master already holds their definitions.
pub fn reply_to_pb(r: &Reply) -> pb::WorkerMessage {
    let reply = match r {
        Reply::Ack => PbReply::Ack(pb::Ack {}),
        Reply::Report(rep) => PbReply::Report(pb::Report {
            bodies: Some(reports_to_pb(&rep.bodies)),
            group_first: rep.groups.iter().map(|g| g.first).collect(),
            group_nanos: rep.groups.iter().map(|g| g.nanos).collect(),
            compute_nanos: rep.compute_ns,
            contacts: Some(contacts_to_pb(&rep.contacts)),
        }),
        Reply::Unloaded(bodies) => PbReply::Unloaded(pb::Bodies {
            states: bodies.iter().map(state_to_pb).collect(),
        }),
        Reply::Snapshot(bodies) => PbReply::Snapshot(pb::Bodies {
            states: bodies.iter().map(state_to_pb).collect(),
        }),
        Reply::Fault { group_first, fault } => PbReply::Failure(pb::Failure {
            kind: Some(pb::failure::Kind::Fault(fault_to_pb(fault))),
            group_first: *group_first,
        }),
        Reply::Error(e) => PbReply::Failure(pb::Failure {
            kind: Some(pb::failure::Kind::Error(e.clone())),
            group_first: 0,
        }),
    };
    pb::WorkerMessage { reply: Some(reply) }
}

/// Decode a step report.
pub fn report_from_pb(r: &pb::Report) -> Result<StepReport, ProtoError> {
    if r.group_first.len() != r.group_nanos.len() {
        return Err(ProtoError::Invalid(
            "report: group columns differ in length".into(),
        ));
    }
    Ok(StepReport {
        bodies: crate::report::reports_from_pb(
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
    })
}
