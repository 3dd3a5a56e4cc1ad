//! Supports, prescribed motion, nodal loads and contacts of a deck, per body.
//!
//! crash prescribes all six DOFs of a node together (`crash_core::VelocityProgram`):
//! a node with prescribed motion on some DOFs must have every other DOF held (by an
//! SPC, *NODE TC/RC) or prescribed too, otherwise the deck means something crash would
//! not do and is refused. A *MAT_RIGID part becomes a kinematic body when its CON1,
//! CON2 and rigid prescribed motion hold all six DOFs; crash has no free rigid bodies.

use super::convert::{
    by_body, dof_axis, dof_bit, dof_names, rigid, sel, ContactOut, Index, LoadOut, Model,
    Prescribe, PressureOut, Sel, ALL,
};
use super::deck::Driven;
use super::lexer::Loc;
use super::{DeckError, DeckOptions};
use crate::curves::Curve;
use std::collections::{BTreeMap, BTreeSet, HashMap};

/// A node's prescribed DOFs: (DOF, VAD, curve, scale factor bits), sorted.
type Signature = Vec<(i64, i64, i64, u64)>;

fn curve(ix: &Index<'_>, d: &Driven) -> Result<Curve, DeckError> {
    ix.deck
        .curves
        .get(&d.lcid)
        .map(|c| Curve {
            points: c.points.clone(),
        })
        .ok_or_else(|| {
            ix.err(
                d.loc,
                &d.keyword,
                format!("LCID: curve {} is not defined (*DEFINE_CURVE)", d.lcid),
            )
        })
}

/// One velocity program from the prescribed DOFs of a node (or a rigid part).
fn combine(ix: &Index<'_>, list: &[&Driven], sel: Sel) -> Result<Prescribe, DeckError> {
    let first = list[0];
    let (mut v, mut w) = ([0.0; 3], [0.0; 3]);
    let same = list.iter().all(|d| d.lcid == first.lcid);
    let displacement = first.vad == 2;
    if let Some(d) = list
        .iter()
        .find(|d| d.vad != first.vad || (displacement && !same))
    {
        return Err(ix.err(d.loc, &d.keyword, format!(
            "DOF {} (VAD {}, LCID {}) differs from DOF {} (VAD {}, LCID {}) of the same node: crash prescribes a node's DOFs with one program, so a prescribed displacement needs the same VAD and curve on every DOF",
            d.dof, d.vad, d.lcid, first.dof, first.vad, first.lcid
        )));
    }
    let mut ramp = None;
    for d in list {
        let c = curve(ix, d)?;
        let scale = if same {
            d.sf
        } else {
            match c.as_ramp() {
                Some(r) if r.t0 == 0.0 && ramp.is_none_or(|t| t == r.t1) => {
                    ramp = Some(r.t1);
                    d.sf * r.value
                }
                _ => {
                    return Err(ix.err(d.loc, &d.keyword, format!(
                        "load curve {} on DOF {} is parsed but not yet supported by the solver core: the DOFs of one node use curves {} of different shapes, and the core runs one velocity program (a ramp from t = 0, then constant) per node",
                        d.lcid, d.dof,
                        list.iter().map(|x| x.lcid.to_string()).collect::<Vec<_>>().join(", ")
                    )))
                }
            }
        };
        let (axis, rot) = dof_axis(d.dof);
        if rot {
            w[axis] = scale;
        } else {
            v[axis] = scale;
        }
    }
    Ok(Prescribe {
        sel,
        v,
        w,
        curve: same.then_some(first.lcid),
        ramp,
        displacement,
        loc: first.loc,
        what: format!("*{}", first.keyword),
    })
}

pub(super) fn supports_and_motion(ix: &Index<'_>, m: &mut Model) -> Result<(), DeckError> {
    let d = ix.deck;
    let end = m.end_time.0;
    // held DOFs per deck node, with the first card that holds any
    let mut held: BTreeMap<usize, (u8, Loc, String)> = BTreeMap::new();
    for (k, n) in d.nodes.iter().enumerate() {
        if n.mask != 0 {
            ix.nodes(super::deck::Target::Node(n.id), n.loc, "NODE")?;
            held.insert(k, (n.mask, n.loc, "NODE (TC, RC)".into()));
        }
    }
    for s in &d.spcs {
        for k in ix.nodes(s.target, s.loc, &s.keyword)? {
            held.entry(k).or_insert((0, s.loc, s.keyword.clone())).0 |= s.mask;
        }
    }
    for (&k, (_, loc, kw)) in &held {
        if let Some((b, _)) = ix.owner[k] {
            if rigid(ix, &m.bodies[b]).is_some() {
                return Err(ix.err(*loc, kw, format!(
                    "node {} belongs to the rigid part {}: constrain a rigid part with CMO, CON1 and CON2 of its *MAT_RIGID",
                    d.nodes[k].id, m.bodies[b].pid
                )));
            }
        }
    }
    let mut per_node: BTreeMap<usize, Vec<&Driven>> = BTreeMap::new();
    let mut per_rigid: BTreeMap<usize, Vec<&Driven>> = BTreeMap::new();
    for mo in &d.motions {
        if let Some(t) = mo.death.filter(|&t| t < end) {
            return Err(ix.err(mo.loc, &mo.keyword, format!(
                "DEATH = {t} is before the end time {end}: releasing a prescribed motion is not supported"
            )));
        }
        curve(ix, mo)?;
        if let super::deck::Target::Part(pid) = mo.target {
            let b = *ix
                .bodies(mo.target, mo.loc, &mo.keyword)?
                .first()
                .unwrap_or(&0);
            if rigid(ix, &m.bodies[b]).is_none() {
                return Err(ix.err(
                    mo.loc,
                    &mo.keyword,
                    format!(
                    "part {pid} is not rigid (*MAT_RIGID): prescribe its nodes with _NODE or _SET"
                ),
                ));
            }
            if mo.dof > 3 {
                return Err(ix.err(mo.loc, &mo.keyword, format!(
                    "DOF {}: a prescribed rotation of a rigid part (about its centre of mass) is not supported", mo.dof
                )));
            }
            per_rigid.entry(b).or_default().push(mo);
            continue;
        }
        for k in ix.nodes(mo.target, mo.loc, &mo.keyword)? {
            if let Some((b, _)) = ix.owner[k] {
                if rigid(ix, &m.bodies[b]).is_some() {
                    return Err(ix.err(mo.loc, &mo.keyword, format!(
                        "node {} belongs to the rigid part {}: use *BOUNDARY_PRESCRIBED_MOTION_RIGID",
                        d.nodes[k].id, m.bodies[b].pid
                    )));
                }
            }
            per_node.entry(k).or_default().push(mo);
        }
    }
    for (b, body) in m.bodies.iter_mut().enumerate() {
        let Some(con) = rigid(ix, body) else { continue };
        let list = per_rigid.remove(&b).unwrap_or_default();
        let pmask = list.iter().fold(0, |a, x| a | dof_bit(x.dof));
        if con | pmask != ALL {
            let mat = &d.mats[&body.mid];
            return Err(ix.err(mat.loc, &mat.keyword, format!(
                "part {} is rigid but DOFs {} are neither constrained (CMO = 1, CON1, CON2) nor prescribed (*BOUNDARY_PRESCRIBED_MOTION_RIGID): crash has no free rigid bodies; hold or prescribe every DOF, or use *MAT_ELASTIC",
                body.pid, dof_names(ALL & !(con | pmask))
            )));
        }
        if list.is_empty() {
            body.fixes.push((
                Sel::All,
                ALL,
                mat_loc(ix, body.mid),
                "*MAT_RIGID (fully constrained)".into(),
            ));
        } else {
            body.prescribes.push(combine(ix, &list, Sel::All)?);
        }
    }
    // nodes: every DOF held or prescribed; group equal programs per body
    let mut groups: BTreeMap<(usize, Signature), Vec<usize>> = BTreeMap::new();
    for (k, list) in &per_node {
        let mut seen = BTreeMap::new();
        for mo in list {
            if let Some(prev) = seen.insert(mo.dof, mo.loc) {
                return Err(ix.err(
                    mo.loc,
                    &mo.keyword,
                    format!(
                        "DOF {} of node {} is already prescribed (at {})",
                        mo.dof,
                        d.nodes[*k].id,
                        d.at(prev)
                    ),
                ));
            }
        }
        let pmask = list.iter().fold(0, |a, x| a | dof_bit(x.dof));
        let hmask = held.get(k).map_or(0, |h| h.0);
        if pmask | hmask != ALL {
            let mo = list[0];
            return Err(ix.err(mo.loc, &mo.keyword, format!(
                "node {}: DOFs {} are neither prescribed nor held: crash prescribes all six DOFs of a node together, so hold them (*BOUNDARY_SPC) or prescribe them too",
                d.nodes[*k].id, dof_names(ALL & !(pmask | hmask))
            )));
        }
        let mut sig: Signature = list
            .iter()
            .map(|x| (x.dof, x.vad, x.lcid, x.sf.to_bits()))
            .collect();
        sig.sort_unstable();
        let b = ix.owner[*k].map_or(0, |o| o.0);
        groups.entry((b, sig)).or_default().push(*k);
    }
    for ((b, _), nodes) in groups {
        let list = &per_node[&nodes[0]];
        let ids = nodes.iter().map(|&k| d.nodes[k].id).collect();
        let s = sel(ids, &m.bodies[b]);
        let p = combine(ix, list, s)?;
        m.bodies[b].prescribes.push(p);
    }
    // supports: group equal masks per body
    let mut fixes: BTreeMap<(usize, u8), (Vec<i64>, Loc, String)> = BTreeMap::new();
    for (k, (mask, loc, kw)) in held {
        let b = ix.owner[k].map_or(0, |o| o.0);
        let e = fixes
            .entry((b, mask))
            .or_insert_with(|| (Vec::new(), loc, kw.clone()));
        if (loc.file, loc.line) < (e.1.file, e.1.line) {
            (e.1, e.2) = (loc, kw);
        }
        e.0.push(d.nodes[k].id);
    }
    for ((b, mask), (ids, loc, kw)) in fixes {
        let s = sel(ids, &m.bodies[b]);
        m.bodies[b].fixes.push((s, mask, loc, format!("*{kw}")));
    }
    Ok(())
}

fn mat_loc(ix: &Index<'_>, mid: i64) -> Loc {
    ix.deck.mats.get(&mid).map_or_else(Loc::default, |m| m.loc)
}

pub(super) fn loads(ix: &Index<'_>, m: &mut Model) -> Result<(), DeckError> {
    for l in &ix.deck.loads {
        curve(ix, l)?;
        let nodes = ix.nodes(l.target, l.loc, &l.keyword)?;
        for (b, ids) in by_body(ix, &nodes) {
            let body = &mut m.bodies[b];
            if rigid(ix, body).is_some() {
                return Err(ix.err(l.loc, &l.keyword, format!(
                    "a load on the rigid part {} does nothing (it is kinematic in crash): refused", body.pid
                )));
            }
            // the scene's force is the total over the selected nodes
            let (axis, rot) = dof_axis(l.dof);
            let mut vec = [0.0; 3];
            vec[axis] = l.sf * ids.len() as f64;
            let s = sel(ids, body);
            body.loads.push(LoadOut {
                sel: s,
                force: (!rot).then_some(vec),
                moment: rot.then_some(vec),
                curve: l.lcid,
                loc: l.loc,
                what: format!("*{}", l.keyword),
            });
        }
    }
    Ok(())
}

/// *LOAD_SHELL_ELEMENT / _SET: per body, the pressure on the named shells (all of the
/// body's shells: no element list, as a scene's pressure on the whole body).
pub(super) fn pressures(ix: &Index<'_>, m: &mut Model) -> Result<(), DeckError> {
    let d = ix.deck;
    if d.pressures.is_empty() {
        return Ok(());
    }
    let part_of: HashMap<i64, i64> = d.shells.iter().map(|s| (s.id, s.part)).collect();
    for p in &d.pressures {
        if !d.curves.contains_key(&p.lcid) {
            return Err(ix.err(
                p.loc,
                &p.keyword,
                format!("LCID: curve {} is not defined (*DEFINE_CURVE)", p.lcid),
            ));
        }
        let mut eids: Vec<i64> = if p.set {
            let s = d.shell_sets.get(&p.id).ok_or_else(|| {
                ix.err(
                    p.loc,
                    &p.keyword,
                    format!("shell set {} is not defined (*SET_SHELL_LIST)", p.id),
                )
            })?;
            let mut v = s.items.clone();
            for &(a, b) in &s.ranges {
                v.extend(
                    d.shells
                        .iter()
                        .map(|e| e.id)
                        .filter(|id| (a..=b).contains(id)),
                );
            }
            v
        } else {
            vec![p.id]
        };
        eids.sort_unstable();
        eids.dedup();
        let mut per_body: BTreeMap<usize, Vec<i64>> = BTreeMap::new();
        for &eid in &eids {
            let part = part_of.get(&eid).ok_or_else(|| {
                ix.err(
                    p.loc,
                    &p.keyword,
                    format!("element {eid} is not defined (*ELEMENT_SHELL)"),
                )
            })?;
            let b = ix.body_of.get(part).copied().unwrap_or(0);
            per_body.entry(b).or_default().push(eid);
        }
        for (b, ids) in per_body {
            let body = &mut m.bodies[b];
            if rigid(ix, body).is_some() {
                return Err(ix.err(p.loc, &p.keyword, format!(
                    "a pressure on the rigid part {} does nothing (it is kinematic in crash): refused", body.pid
                )));
            }
            let all = ids.len() == body.surface.element_tags.len();
            body.pressures.push(PressureOut {
                elements: (!all).then_some(ids),
                value: p.sf,
                curve: p.lcid,
                loc: p.loc,
                what: format!("*{}", p.keyword),
            });
        }
    }
    Ok(())
}

pub(super) fn contacts(ix: &Index<'_>, m: &mut Model, opts: &DeckOptions) -> Result<(), DeckError> {
    let d = ix.deck;
    let Some(first) = d.contacts.first() else {
        return Ok(());
    };
    let mut wanted: BTreeSet<(usize, usize)> = BTreeSet::new();
    for c in &d.contacts {
        if c.fs != 0.0 || c.fd != 0.0 {
            let what = format!(
                "friction FS = {}, FD = {}: crash's contact is frictionless",
                c.fs, c.fd
            );
            if !opts.ignore_friction {
                return Err(ix.err(c.loc, &c.keyword, format!(
                    "{what}; set FS and FD to 0, or run with --ignore-friction to run without friction"
                )));
            }
            m.notes.push(format!(
                "warning: {}: *{}: {what}; the friction is ignored (--ignore-friction)",
                d.at(c.loc),
                c.keyword
            ));
        }
        if let Some(t) = c.death.filter(|&t| t < m.end_time.0) {
            return Err(ix.err(
                c.loc,
                &c.keyword,
                format!("DT = {t} is before the end time: a contact that stops is not supported"),
            ));
        }
        if c.vdc != first.vdc {
            return Err(ix.err(c.loc, &c.keyword, format!(
                "VDC = {} differs from {} of the contact at {}: crash has one contact damping for the scene",
                c.vdc, first.vdc, d.at(first.loc)
            )));
        }
        let a = ix.bodies(c.a, c.loc, &c.keyword)?;
        let b = match c.b {
            Some(t) => ix.bodies(t, c.loc, &c.keyword)?,
            None => a.clone(),
        };
        for &x in a.iter().chain(&b) {
            m.bodies[x].contact = true;
            if c.single {
                m.bodies[x].self_contact = true;
            }
        }
        for &x in &a {
            for &y in &b {
                if x != y || c.single {
                    wanted.insert((x.min(y), x.max(y)));
                }
            }
        }
    }
    let on: Vec<usize> = (0..m.bodies.len())
        .filter(|&b| m.bodies[b].contact)
        .collect();
    let mut extra = Vec::new();
    for (i, &x) in on.iter().enumerate() {
        for &y in &on[i..] {
            let crash_does = x != y || m.bodies[x].self_contact;
            if crash_does && !wanted.contains(&(x, y)) {
                extra.push(format!(
                    "\"{}\" - \"{}\"",
                    m.bodies[x].name, m.bodies[y].name
                ));
            }
        }
    }
    if !extra.is_empty() {
        m.notes.push(format!(
            "crash checks contact between every two contact bodies: {} also in contact, though no *CONTACT names that pair",
            extra.join(", ")
        ));
    }
    m.contact = Some(ContactOut {
        damping_ratio: first.vdc / 100.0,
        loc: first.loc,
    });
    Ok(())
}
