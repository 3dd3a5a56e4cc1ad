//! Readers of supports (*BOUNDARY_SPC), prescribed motion, nodal loads and initial
//! velocities.

use super::cards::{i, r, Row, F};
use super::deck::{Cards, Deck, Driven, InitialVelocity, ShellPressure, Spc, Target};
use super::DeckError;

#[rustfmt::skip]
const SPC: &[F] = &[
    i("NID/NSID", 10), i("CID", 10), r("DOFX", 10), r("DOFY", 10), r("DOFZ", 10),
    r("DOFRX", 10), r("DOFRY", 10), r("DOFRZ", 10)
];

pub fn spc(deck: &mut Deck, c: &mut Cards<'_>, set: bool) -> Result<(), DeckError> {
    while let Some(row) = c.next(SPC)? {
        if (0..8).all(|k| row.raw(k).is_empty()) {
            continue;
        }
        let id = row.id(0)?;
        row.unsupported(1, "a local coordinate system (CID)")?;
        let mut mask = 0u8;
        for k in 0..6 {
            match row.flag(2 + k)? {
                0 => {}
                1 => mask |= 1 << k,
                v => return Err(row.err(2 + k, format!("{v}: must be 0 (free) or 1 (held)"))),
            }
        }
        deck.spcs.push(Spc {
            target: if set {
                Target::NodeSet(id)
            } else {
                Target::Node(id)
            },
            mask,
            keyword: c.b.name.clone(),
            loc: row.loc,
        });
    }
    Ok(())
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    MotionNode,
    MotionSet,
    MotionRigid,
    LoadNode,
    LoadSet,
}

#[rustfmt::skip]
const MOTION: &[F] = &[
    i("ID", 10), i("DOF", 10), i("VAD", 10), i("LCID", 10), r("SF", 10), i("VID", 10),
    r("DEATH", 10), r("BIRTH", 10)
];
#[rustfmt::skip]
const LOAD: &[F] = &[
    i("ID", 10), i("DOF", 10), i("LCID", 10), r("SF", 10), i("CID", 10), i("M1", 10),
    i("M2", 10), i("M3", 10)
];

/// DOF 1..3 (translations) and 5..7 (rotations), as LS-DYNA numbers them.
fn dof(row: &Row<'_>, k: usize, what: &str) -> Result<i64, DeckError> {
    match row.int_or(k, 0)? {
        d @ (1..=3 | 5..=7) => Ok(d),
        d => Err(row.err(
            k,
            format!("{d}: only 1, 2, 3 (x, y, z) and 5, 6, 7 (rotations about x, y, z) are supported for {what}"),
        )),
    }
}

/// A zero scale factor means LS-DYNA's default 1 (a blank field reads as 0).
fn sf(row: &Row<'_>, k: usize) -> Result<f64, DeckError> {
    Ok(Some(row.real_or(k, 0.0)?)
        .filter(|&v| v != 0.0)
        .unwrap_or(1.0))
}

pub fn driven(deck: &mut Deck, c: &mut Cards<'_>, kind: Kind) -> Result<(), DeckError> {
    let motion = matches!(kind, Kind::MotionNode | Kind::MotionSet | Kind::MotionRigid);
    let layout = if motion { MOTION } else { LOAD };
    while let Some(row) = c.next(layout)? {
        if (0..8).all(|k| row.raw(k).is_empty()) {
            continue;
        }
        let id = row.id(0)?;
        let target = match kind {
            Kind::MotionNode | Kind::LoadNode => Target::Node(id),
            Kind::MotionSet | Kind::LoadSet => Target::NodeSet(id),
            Kind::MotionRigid => Target::Part(id),
        };
        let mut vad = 0;
        let d = if motion {
            let d = dof(&row, 1, "prescribed motion")?;
            vad = match row.int_or(2, 0)? {
                v @ (0 | 2) => v,
                v => return Err(row.err(2, format!("{v}: only prescribed velocities (VAD = 0) and displacements (VAD = 2) are supported (1: acceleration)"))),
            };
            if vad == 2 && d > 3 {
                return Err(row.err(1, format!("{d}: a prescribed rotation angle (VAD = 2 on a rotational DOF) is not supported")));
            }
            row.unsupported(5, "a direction vector (VID)")?;
            row.unsupported(7, "a birth time (BIRTH)")?;
            d
        } else {
            let d = dof(&row, 1, "nodal loads")?;
            row.unsupported_all(&[
                (4, "a local coordinate system (CID)"),
                (5, "follower-force nodes (M1)"),
                (6, "M2"),
                (7, "M3"),
            ])?;
            d
        };
        let lk = if motion { 3 } else { 2 };
        let lcid = row.id(lk)?;
        let death = if motion {
            row.real(6)?.filter(|&v| v != 0.0 && v < 1e28)
        } else {
            None
        };
        let rec = Driven {
            target,
            dof: d,
            vad,
            lcid,
            sf: sf(&row, if motion { 4 } else { 3 })?,
            death,
            keyword: c.b.name.clone(),
            loc: row.loc,
        };
        if motion {
            deck.motions.push(rec);
        } else {
            deck.loads.push(rec);
        }
    }
    Ok(())
}

#[rustfmt::skip]
const SHELL_LOAD: &[F] = &[i("EID/ESID", 10), i("LCID", 10), r("SF", 10), r("AT", 10)];

/// *LOAD_SHELL_ELEMENT (`set`: false) and *LOAD_SHELL_SET: pressure SF x curve LCID.
pub fn shell_pressure(deck: &mut Deck, c: &mut Cards<'_>, set: bool) -> Result<(), DeckError> {
    while let Some(row) = c.next(SHELL_LOAD)? {
        if (0..4).all(|k| row.raw(k).is_empty()) {
            continue;
        }
        let id = row.id(0)?;
        // an arrival (birth) time would switch the pressure on with a jump at AT
        row.unsupported(3, "an arrival time (AT; shift the curve instead)")?;
        deck.pressures.push(ShellPressure {
            id,
            set,
            lcid: row.id(1)?,
            sf: sf(&row, 2)?,
            keyword: c.b.name.clone(),
            loc: row.loc,
        });
    }
    Ok(())
}

#[rustfmt::skip]
const IV1: &[F] = &[i("NSID", 10), i("NSIDEX", 10), i("BOXID", 10), i("IRIGID", 10), i("ICID", 10)];
#[rustfmt::skip]
const IV2: &[F] = &[
    r("VX", 10), r("VY", 10), r("VZ", 10), r("VXR", 10), r("VYR", 10), r("VZR", 10)
];

pub fn velocity(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    let head = c.need(IV1, "NSID")?;
    head.unsupported_all(&[
        (1, "an exempted node set (NSIDEX)"),
        (2, "a box (BOXID)"),
        (3, "IRIGID"),
        (4, "a local coordinate system (ICID)"),
    ])?;
    let nsid = head.int_or(0, 0)?;
    let v = c.need(IV2, "VX VY VZ")?;
    v.unsupported_all(&[
        (
            3,
            "a nodal rotational velocity (VXR; use *INITIAL_VELOCITY_GENERATION for a spin)",
        ),
        (4, "VYR"),
        (5, "VZR"),
    ])?;
    deck.velocities.push(InitialVelocity {
        target: if nsid > 0 {
            Target::NodeSet(nsid)
        } else {
            Target::All
        },
        v: [v.real_or(0, 0.0)?, v.real_or(1, 0.0)?, v.real_or(2, 0.0)?],
        omega: [0.0; 3],
        centre: [0.0; 3],
        keyword: c.b.name.clone(),
        loc: head.loc,
    });
    c.done()
}

#[rustfmt::skip]
const GEN1: &[F] = &[
    i("ID", 10), i("STYP", 10), r("OMEGA", 10), r("VX", 10), r("VY", 10), r("VZ", 10),
    i("IVATN", 10), i("ICID", 10)
];
#[rustfmt::skip]
const GEN2: &[F] = &[
    r("XC", 10), r("YC", 10), r("ZC", 10), r("NX", 10), r("NY", 10), r("NZ", 10),
    i("PHASE", 10), i("IRIGID", 10)
];

pub fn generation(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    while let Some(row) = c.next(GEN1)? {
        let id = row.id(0)?;
        let target = match row.int_or(1, 0)? {
            1 => Target::PartSet(id),
            2 => Target::Part(id),
            3 => Target::NodeSet(id),
            s => {
                return Err(row.err(
                    1,
                    format!("{s}: must be 1 (part set), 2 (part) or 3 (node set)"),
                ))
            }
        };
        row.unsupported_all(&[(6, "IVATN"), (7, "a local coordinate system (ICID)")])?;
        let g = c.need(GEN2, "XC YC ZC NX NY NZ")?;
        g.unsupported_all(&[(6, "PHASE (after dynamic relaxation)"), (7, "IRIGID")])?;
        let omega = row.real_or(2, 0.0)?;
        let n = [g.real_or(3, 0.0)?, g.real_or(4, 0.0)?, g.real_or(5, 0.0)?];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if omega != 0.0 && !(len > 0.0 && len.is_finite()) {
            return Err(g.err(
                3,
                "the rotation axis NX NY NZ must be a non-zero vector when OMEGA is not 0",
            ));
        }
        let axis = if omega == 0.0 {
            [0.0; 3]
        } else {
            n.map(|x| omega * x / len)
        };
        deck.velocities.push(InitialVelocity {
            target,
            v: [
                row.real_or(3, 0.0)?,
                row.real_or(4, 0.0)?,
                row.real_or(5, 0.0)?,
            ],
            omega: axis,
            centre: [g.real_or(0, 0.0)?, g.real_or(1, 0.0)?, g.real_or(2, 0.0)?],
            keyword: c.b.name.clone(),
            loc: row.loc,
        });
    }
    Ok(())
}
