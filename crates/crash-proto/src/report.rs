//! Step reports and faults <-> wire.

use crate::body::vec3;
use crate::error::ProtoError;
use crate::pb;
use crate::pb::fault::Kind;
use crash_core::contact::{KinLoad, PairStats, Tally};
use crash_core::{BodyEnergy, BodyReport, Fault, NodeProbe, Reaction};

const VALUES: usize = 15;
const ELEMENTS: usize = 2;
/// Force, moment, moment about the origin.
const REACTION_VALUES: usize = 9;

/// Column-pack the per-body reports of one worker.
pub fn reports_to_pb(reports: &[BodyReport]) -> pb::BodyReports {
    let n = reports.len();
    let mut out = pb::BodyReports {
        id: Vec::with_capacity(n),
        values: Vec::with_capacity(VALUES * n),
        elements: Vec::with_capacity(ELEMENTS * n),
        reaction_index: Vec::new(),
        reactions: Vec::new(),
    };
    for (k, r) in reports.iter().enumerate() {
        if let Some(re) = r.reaction {
            out.reaction_index.push(k as u32);
            for v in [re.force, re.moment, re.moment_origin] {
                out.reactions.extend_from_slice(&[v.x, v.y, v.z]);
            }
        }
        let e = &r.energy;
        out.id.push(r.id);
        out.values.extend_from_slice(&[
            e.kinetic,
            e.internal,
            e.hourglass,
            e.contact,
            e.damping,
            e.external,
            r.stable_dt,
            r.lo.x,
            r.lo.y,
            r.lo.z,
            r.hi.x,
            r.hi.y,
            r.hi.z,
            r.max_move,
            r.hot_density,
        ]);
        out.elements
            .extend_from_slice(&[r.dt_element as u64, r.hot_element as u64]);
    }
    out
}

fn index(v: u64) -> Result<usize, ProtoError> {
    usize::try_from(v).map_err(|_| ProtoError::Invalid(format!("index {v} out of range")))
}

pub fn reports_from_pb(p: &pb::BodyReports) -> Result<Vec<BodyReport>, ProtoError> {
    let n = p.id.len();
    if p.values.len() != VALUES * n || p.elements.len() != ELEMENTS * n {
        return Err(ProtoError::Invalid(format!(
            "report of {n} bodies has {} values and {} element indices",
            p.values.len(),
            p.elements.len()
        )));
    }
    let mut out = Vec::with_capacity(n);
    for ((&id, v), e) in
        p.id.iter()
            .zip(p.values.chunks_exact(VALUES))
            .zip(p.elements.chunks_exact(ELEMENTS))
    {
        out.push(BodyReport {
            id,
            energy: BodyEnergy {
                kinetic: v[0],
                internal: v[1],
                hourglass: v[2],
                contact: v[3],
                damping: v[4],
                external: v[5],
            },
            stable_dt: v[6],
            dt_element: index(e[0])?,
            lo: vec3(&v[7..10]),
            hi: vec3(&v[10..13]),
            max_move: v[13],
            hot_element: index(e[1])?,
            hot_density: v[14],
            reaction: None,
        });
    }
    if p.reactions.len() != REACTION_VALUES * p.reaction_index.len() {
        return Err(ProtoError::Invalid(format!(
            "{} reactions carry {} values",
            p.reaction_index.len(),
            p.reactions.len()
        )));
    }
    for (&k, v) in p
        .reaction_index
        .iter()
        .zip(p.reactions.chunks_exact(REACTION_VALUES))
    {
        let r = out
            .get_mut(k as usize)
            .ok_or_else(|| ProtoError::Invalid(format!("reaction of body {k} of {n}")))?;
        r.reaction = Some(Reaction {
            force: vec3(&v[0..3]),
            moment: vec3(&v[3..6]),
            moment_origin: vec3(&v[6..9]),
        });
    }
    Ok(out)
}

const CONTACT_VALUES: usize = 8;
/// Stride of `ContactStats::kin_programs` (pair index, side, program, force[3]) and of
/// `kin_nodes` (pair index, side, node, force[3]).
const KIN_VALUES: usize = 6;
/// Words of `ContactStats::tally` per pair: four i128 sums, high and low halves.
const TALLY_WORDS: usize = 8;

/// Column-pack contact statistics.
pub fn contacts_to_pb(stats: &[PairStats]) -> pb::ContactStats {
    let mut out = pb::ContactStats {
        pairs: Vec::with_capacity(2 * stats.len()),
        active_nodes: Vec::with_capacity(stats.len()),
        values: Vec::with_capacity(CONTACT_VALUES * stats.len()),
        kin_programs: Vec::new(),
        kin_nodes: Vec::new(),
        tally: Vec::with_capacity(TALLY_WORDS * stats.len()),
    };
    for (k, s) in stats.iter().enumerate() {
        for v in [
            s.tally.normal,
            s.tally.on_a[0],
            s.tally.on_a[1],
            s.tally.on_a[2],
        ] {
            out.tally.extend_from_slice(&[(v >> 64) as u64, v as u64]);
        }
        out.pairs.extend_from_slice(&[s.a, s.b]);
        out.active_nodes.push(s.active_nodes as u64);
        out.values.extend_from_slice(&[
            s.max_penetration,
            s.max_penetration_ratio,
            s.normal_force,
            s.force_on_a.x,
            s.force_on_a.y,
            s.force_on_a.z,
            s.kin_a.power,
            s.kin_b.power,
        ]);
        for (side, l) in [(0.0, &s.kin_a), (1.0, &s.kin_b)] {
            for (p, f) in &l.by_program {
                out.kin_programs
                    .extend_from_slice(&[k as f64, side, f64::from(*p), f.x, f.y, f.z]);
            }
            for (n, f) in &l.nodes {
                out.kin_nodes
                    .extend_from_slice(&[k as f64, side, f64::from(*n), f.x, f.y, f.z]);
            }
        }
    }
    out
}

pub fn contacts_from_pb(p: &pb::ContactStats) -> Result<Vec<PairStats>, ProtoError> {
    let n = p.active_nodes.len();
    if p.pairs.len() != 2 * n
        || p.values.len() != CONTACT_VALUES * n
        || p.tally.len() != TALLY_WORDS * n
    {
        return Err(ProtoError::Invalid(format!(
            "contact statistics of {n} pairs have {} ids, {} values and {} sum words",
            p.pairs.len(),
            p.values.len(),
            p.tally.len()
        )));
    }
    let mut out = Vec::with_capacity(n);
    for (((ab, &active), v), t) in p
        .pairs
        .chunks_exact(2)
        .zip(&p.active_nodes)
        .zip(p.values.chunks_exact(CONTACT_VALUES))
        .zip(p.tally.chunks_exact(TALLY_WORDS))
    {
        let word = |k: usize| (i128::from(t[2 * k] as i64) << 64) | i128::from(t[2 * k + 1]);
        out.push(PairStats {
            a: ab[0],
            b: ab[1],
            active_nodes: index(active)?,
            max_penetration: v[0],
            max_penetration_ratio: v[1],
            normal_force: v[2],
            force_on_a: vec3(&v[3..6]),
            tally: Tally {
                normal: word(0),
                on_a: [word(1), word(2), word(3)],
            },
            kin_a: KinLoad {
                power: v[6],
                ..KinLoad::default()
            },
            kin_b: KinLoad {
                power: v[7],
                ..KinLoad::default()
            },
        });
    }
    for (what, values) in [("program", &p.kin_programs), ("node", &p.kin_nodes)] {
        if values.len() % KIN_VALUES != 0 {
            return Err(ProtoError::Invalid(format!(
                "kinematic loads per {what} hold {} values, not a multiple of {KIN_VALUES}",
                values.len()
            )));
        }
        for v in values.chunks_exact(KIN_VALUES) {
            let (k, side, id) = (v[0], v[1], v[2]);
            let max = if what == "program" {
                f64::from(u16::MAX)
            } else {
                f64::from(u32::MAX)
            };
            if !(k >= 0.0 && k < n as f64 && k.fract() == 0.0)
                || !(side == 0.0 || side == 1.0)
                || !(id >= 0.0 && id <= max && id.fract() == 0.0)
            {
                return Err(ProtoError::Invalid(format!(
                    "kinematic load per {what} {v:?} names no pair, side or {what}"
                )));
            }
            let s = &mut out[k as usize];
            let l = if side == 0.0 {
                &mut s.kin_a
            } else {
                &mut s.kin_b
            };
            // kept in the sender's order (sorted)
            if what == "program" {
                l.by_program.push((id as u16, vec3(&v[3..6])));
            } else {
                l.nodes.push((id as u32, vec3(&v[3..6])));
            }
        }
    }
    Ok(out)
}

pub fn fault_to_pb(f: &Fault) -> pb::Fault {
    let (step, body, kind) = match f {
        Fault::NonFinite {
            step,
            body,
            place,
            what,
        } => (
            *step,
            *body,
            Kind::NonFinite(pb::NonFinite {
                place: place.clone(),
                what: (*what).into(),
            }),
        ),
        Fault::Collapsed {
            step,
            body,
            element,
            ratio,
        } => (
            *step,
            *body,
            Kind::Collapsed(pb::Collapsed {
                element: *element as u64,
                ratio: *ratio,
            }),
        ),
        Fault::Inverted {
            step,
            body,
            element,
            corner,
        } => (
            *step,
            *body,
            Kind::Inverted(pb::Inverted {
                element: *element as u64,
                corner: *corner as u64,
            }),
        ),
        Fault::EnergyRunaway {
            step,
            error,
            limit,
            body,
            element,
        } => (
            *step,
            *body,
            Kind::EnergyRunaway(pb::EnergyRunaway {
                error: *error,
                limit: *limit,
                element: *element as u64,
            }),
        ),
        Fault::DtCollapse {
            step,
            dt,
            floor,
            body,
            element,
        } => (
            *step,
            *body,
            Kind::DtCollapse(pb::DtCollapse {
                dt: *dt,
                floor: *floor,
                element: *element as u64,
            }),
        ),
        Fault::Tunnelling {
            step,
            body,
            node,
            speed,
            distance,
            budget,
        } => (
            *step,
            *body,
            Kind::Tunnelling(pb::Tunnelling {
                node: *node as u64,
                speed: *speed,
                distance: *distance,
                budget: *budget,
            }),
        ),
        Fault::PassThrough {
            step,
            body,
            body_name,
            node,
            other,
            other_name,
            segment,
            closing_speed,
        } => (
            *step,
            *body,
            Kind::PassThrough(pb::PassThrough {
                body_name: body_name.clone(),
                node: *node as u64,
                other: *other,
                other_name: other_name.clone(),
                segment: *segment as u64,
                closing_speed: *closing_speed,
            }),
        ),
    };
    pb::Fault {
        step,
        body,
        kind: Some(kind),
    }
}

/// `Fault::NonFinite::what` is a static string: the known texts map back to themselves;
/// another text (a newer peer) is kept by leaking it once (a fault ends the run).
fn static_text(s: &str) -> &'static str {
    const KNOWN: [&str; 2] = ["internal energy", "velocity or position"];
    match KNOWN.iter().find(|k| **k == s) {
        Some(k) => k,
        None => Box::leak(s.to_owned().into_boxed_str()),
    }
}

pub fn fault_from_pb(p: &pb::Fault) -> Result<Fault, ProtoError> {
    let (step, body) = (p.step, p.body);
    Ok(
        match p.kind.as_ref().ok_or(ProtoError::Missing("fault.kind"))? {
            Kind::NonFinite(k) => Fault::NonFinite {
                step,
                body,
                place: k.place.clone(),
                what: static_text(&k.what),
            },
            Kind::Collapsed(k) => Fault::Collapsed {
                step,
                body,
                element: index(k.element)?,
                ratio: k.ratio,
            },
            Kind::Inverted(k) => Fault::Inverted {
                step,
                body,
                element: index(k.element)?,
                corner: index(k.corner)?,
            },
            Kind::EnergyRunaway(k) => Fault::EnergyRunaway {
                step,
                error: k.error,
                limit: k.limit,
                body,
                element: index(k.element)?,
            },
            Kind::DtCollapse(k) => Fault::DtCollapse {
                step,
                dt: k.dt,
                floor: k.floor,
                body,
                element: index(k.element)?,
            },
            Kind::Tunnelling(k) => Fault::Tunnelling {
                step,
                body,
                node: index(k.node)?,
                speed: k.speed,
                distance: k.distance,
                budget: k.budget,
            },
            Kind::PassThrough(k) => Fault::PassThrough {
                step,
                body,
                body_name: k.body_name.clone(),
                node: index(k.node)?,
                other: k.other,
                other_name: k.other_name.clone(),
                segment: index(k.segment)?,
                closing_speed: k.closing_speed,
            },
        },
    )
}

/// Column-pack history node rows.
pub fn probes_to_pb(rows: &[NodeProbe]) -> pb::NodeProbes {
    let mut out = pb::NodeProbes {
        body: Vec::with_capacity(rows.len()),
        node: Vec::with_capacity(rows.len()),
        values: Vec::with_capacity(9 * rows.len()),
    };
    for r in rows {
        out.body.push(r.body);
        out.node.push(r.node);
        for v in [r.u, r.v, r.a] {
            out.values.extend_from_slice(&[v.x, v.y, v.z]);
        }
    }
    out
}

pub fn probes_from_pb(p: &pb::NodeProbes) -> Result<Vec<NodeProbe>, ProtoError> {
    let n = p.body.len();
    if p.node.len() != n || p.values.len() != 9 * n {
        return Err(ProtoError::Invalid(format!(
            "{n} history nodes carry {} node ids and {} values",
            p.node.len(),
            p.values.len()
        )));
    }
    Ok(p.body
        .iter()
        .zip(&p.node)
        .zip(p.values.chunks_exact(9))
        .map(|((&body, &node), v)| NodeProbe {
            body,
            node,
            u: vec3(&v[0..3]),
            v: vec3(&v[3..6]),
            a: vec3(&v[6..9]),
        })
        .collect())
}
