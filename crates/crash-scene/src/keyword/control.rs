//! Readers of the keywords that act on the model: supports, prescribed motion, nodal
//! loads, initial velocities, contacts, run controls and outputs.

use super::cards::{i, r, t, Row, F};
use super::deck::{Cards, Contact, Db, Deck, Driven, InitialVelocity, Spc, Target};
use super::readers::{ids, LIST8};
use super::DeckError;

/// Read a block whose keyword is one of these (None: not one of them).
pub fn block(deck: &mut Deck, c: &mut Cards<'_>, name: &str) -> Option<Result<(), DeckError>> {
    Some(match name {
        "BOUNDARY_SPC_NODE" => spc(deck, c, false),
        "BOUNDARY_SPC_SET" => spc(deck, c, true),
        "BOUNDARY_PRESCRIBED_MOTION_NODE" => driven(deck, c, Kind::MotionNode),
        "BOUNDARY_PRESCRIBED_MOTION_SET" => driven(deck, c, Kind::MotionSet),
        "BOUNDARY_PRESCRIBED_MOTION_RIGID" => driven(deck, c, Kind::MotionRigid),
        "LOAD_NODE_POINT" => driven(deck, c, Kind::LoadNode),
        "LOAD_NODE_SET" => driven(deck, c, Kind::LoadSet),
        "INITIAL_VELOCITY" => velocity(deck, c),
        "INITIAL_VELOCITY_GENERATION" => generation(deck, c),
        "CONTACT_AUTOMATIC_SINGLE_SURFACE" => contact(deck, c, true, false),
        "CONTACT_AUTOMATIC_SINGLE_SURFACE_ID" => contact(deck, c, true, true),
        "CONTACT_AUTOMATIC_SURFACE_TO_SURFACE" => contact(deck, c, false, false),
        "CONTACT_AUTOMATIC_SURFACE_TO_SURFACE_ID" => contact(deck, c, false, true),
        "CONTROL_TERMINATION" => termination(deck, c),
        "CONTROL_TIMESTEP" => timestep(deck, c),
        "DATABASE_BINARY_D3PLOT" => d3plot(deck, c),
        "DATABASE_GLSTAT" => database(deck, c, Db::Glstat),
        "DATABASE_MATSUM" => database(deck, c, Db::Matsum),
        "DATABASE_RCFORC" => database(deck, c, Db::Rcforc),
        "DATABASE_NODOUT" => database(deck, c, Db::Nodout),
        "DATABASE_SPCFORC" => database(deck, c, Db::Spcforc),
        "DATABASE_HISTORY_NODE" => history(deck, c),
        _ => return None,
    })
}

const SPC: &[F] = &[
    i("NID/NSID", 10),
    i("CID", 10),
    r("DOFX", 10),
    r("DOFY", 10),
    r("DOFZ", 10),
    r("DOFRX", 10),
    r("DOFRY", 10),
    r("DOFRZ", 10),
];

fn spc(deck: &mut Deck, c: &mut Cards<'_>, set: bool) -> Result<(), DeckError> {
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
enum Kind {
    MotionNode,
    MotionSet,
    MotionRigid,
    LoadNode,
    LoadSet,
}

const MOTION: &[F] = &[
    i("ID", 10),
    i("DOF", 10),
    i("VAD", 10),
    i("LCID", 10),
    r("SF", 10),
    i("VID", 10),
    r("DEATH", 10),
    r("BIRTH", 10),
];
const LOAD: &[F] = &[
    i("ID", 10),
    i("DOF", 10),
    i("LCID", 10),
    r("SF", 10),
    i("CID", 10),
    i("M1", 10),
    i("M2", 10),
    i("M3", 10),
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

fn driven(deck: &mut Deck, c: &mut Cards<'_>, kind: Kind) -> Result<(), DeckError> {
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
        let d = if motion {
            let d = dof(&row, 1, "prescribed motion")?;
            match row.int_or(2, 0)? {
                0 => {}
                v => return Err(row.err(2, format!("{v}: only prescribed velocities (VAD = 0) are supported (1: acceleration, 2: displacement)"))),
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

const IV1: &[F] = &[
    i("NSID", 10),
    i("NSIDEX", 10),
    i("BOXID", 10),
    i("IRIGID", 10),
    i("ICID", 10),
];
const IV2: &[F] = &[
    r("VX", 10),
    r("VY", 10),
    r("VZ", 10),
    r("VXR", 10),
    r("VYR", 10),
    r("VZR", 10),
];

fn velocity(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
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

const GEN1: &[F] = &[
    i("ID", 10),
    i("STYP", 10),
    r("OMEGA", 10),
    r("VX", 10),
    r("VY", 10),
    r("VZ", 10),
    i("IVATN", 10),
    i("ICID", 10),
];
const GEN2: &[F] = &[
    r("XC", 10),
    r("YC", 10),
    r("ZC", 10),
    r("NX", 10),
    r("NY", 10),
    r("NZ", 10),
    i("PHASE", 10),
    i("IRIGID", 10),
];

fn generation(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
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

const CID: &[F] = &[i("CID", 10), t("HEADING", 70)];
const C1: &[F] = &[
    i("SSID", 10),
    i("MSID", 10),
    i("SSTYP", 10),
    i("MSTYP", 10),
    i("SBOXID", 10),
    i("MBOXID", 10),
    i("SPR", 10),
    i("MPR", 10),
];
const C2: &[F] = &[
    r("FS", 10),
    r("FD", 10),
    r("DC", 10),
    r("VC", 10),
    r("VDC", 10),
    i("PENCHK", 10),
    r("BT", 10),
    r("DT", 10),
];
const C3: &[F] = &[
    r("SFS", 10),
    r("SFM", 10),
    r("SST", 10),
    r("MST", 10),
    r("SFST", 10),
    r("SFMT", 10),
    r("FSF", 10),
    r("VSF", 10),
];

/// A contact side: part set (2), part (3), all parts (5).
fn side(row: &Row<'_>, idk: usize, typk: usize, single: bool) -> Result<Target, DeckError> {
    let id = row.int_or(idk, 0)?;
    match row.int_or(typk, 0)? {
        2 if id > 0 => Ok(Target::PartSet(id)),
        3 if id > 0 => Ok(Target::Part(id)),
        5 if single => Ok(Target::All),
        2 | 3 => Err(row.err(idk, "a part or part set id (> 0) is required")),
        ty => Err(row.err(
            typk,
            format!("{ty}: only parts (3), part sets (2) and, for a single surface, all parts (5) are supported (segment, shell and node sets are not)"),
        )),
    }
}

fn contact(deck: &mut Deck, c: &mut Cards<'_>, single: bool, id: bool) -> Result<(), DeckError> {
    if id {
        c.need(CID, "CID HEADING")?;
    }
    let a = c.need(C1, "SSID MSID SSTYP MSTYP")?;
    let sa = side(&a, 0, 2, single)?;
    let sb = if single {
        a.unsupported(1, "a second side (MSID) of a single surface")?;
        a.unsupported(3, "MSTYP of a single surface")?;
        None
    } else {
        Some(side(&a, 1, 3, false)?)
    };
    a.unsupported_all(&[(4, "a box (SBOXID)"), (5, "a box (MBOXID)")])?;
    let mut rec = Contact {
        single,
        a: sa,
        b: sb,
        fs: 0.0,
        fd: 0.0,
        vdc: 0.0,
        death: None,
        keyword: c.b.name.clone(),
        loc: a.loc,
    };
    if let Some(b) = c.next(C2)? {
        rec.fs = b.real_or(0, 0.0)?;
        rec.fd = b.real_or(1, 0.0)?;
        rec.vdc = b.real_or(4, 0.0)?;
        if !(0.0..=100.0).contains(&rec.vdc) {
            return Err(b.err(
                4,
                format!("{}: must be in [0, 100] (% of critical damping)", rec.vdc),
            ));
        }
        if rec.fs != 0.0 || rec.fd != 0.0 {
            b.unsupported(2, "a friction decay coefficient (DC)")?;
        }
        b.unsupported_all(&[
            (3, "viscous friction (VC)"),
            (5, "a penetration check (PENCHK)"),
            (6, "a birth time (BT)"),
        ])?;
        rec.death = b.real(7)?.filter(|&v| v != 0.0 && v < 1e20);
    }
    if let Some(s) = c.next(C3)? {
        for (k, name) in [
            (0, "SFS"),
            (1, "SFM"),
            (4, "SFST"),
            (5, "SFMT"),
            (6, "FSF"),
            (7, "VSF"),
        ] {
            let v = s.real_or(k, 0.0)?;
            if v != 0.0 && v != 1.0 {
                return Err(s.err(k, format!("{v}: scale factors other than 1 are not supported ({name}; crash's penalty is set by [contact] penalty_scale)")));
            }
        }
        s.unsupported_all(&[
            (2, "a contact thickness (SST)"),
            (3, "a contact thickness (MST)"),
        ])?;
    }
    deck.contacts.push(rec);
    c.done()
}

const TERM: &[F] = &[
    r("ENDTIM", 10),
    i("ENDCYC", 10),
    r("DTMIN", 10),
    r("ENDENG", 10),
    r("ENDMAS", 10),
    i("NOSOL", 10),
];

fn termination(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    let row = c.need(TERM, "ENDTIM")?;
    row.unsupported_all(&[
        (1, "a cycle limit (ENDCYC)"),
        (2, "DTMIN"),
        (3, "ENDENG"),
        (4, "ENDMAS"),
        (5, "NOSOL"),
    ])?;
    deck.end_time = Some((row.real_or(0, 0.0)?, row.loc));
    c.done()
}

const TS1: &[F] = &[
    r("DTINIT", 10),
    r("TSSFAC", 10),
    i("ISDO", 10),
    r("TSLIMT", 10),
    r("DT2MS", 10),
    i("LCTM", 10),
    i("ERODE", 10),
    i("MS1ST", 10),
];
const TS2: &[F] = &[
    r("DT2MSF", 10),
    i("DT2MSLC", 10),
    i("IMSCL", 10),
    r("UNUSED", 10),
    r("UNUSED", 10),
    r("RMSCL", 10),
    r("UNUSED", 10),
    i("IHDO", 10),
];

fn timestep(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    let row = c.need(TS1, "DTINIT TSSFAC")?;
    row.unsupported_all(&[
        (0, "an initial time step (DTINIT)"),
        (2, "ISDO"),
        (3, "TSLIMT"),
        (4, "mass scaling (DT2MS)"),
        (5, "a time step curve (LCTM)"),
        (6, "erosion (ERODE)"),
        (7, "MS1ST"),
    ])?;
    if let Some(r2) = c.next(TS2)? {
        for k in 0..8 {
            r2.unsupported(k, "the second *CONTROL_TIMESTEP card")?;
        }
    }
    if let Some(s) = row.real(1)?.filter(|&v| v != 0.0) {
        deck.tssfac = Some((s, row.loc));
    }
    c.done()
}

const D3: &[F] = &[
    r("DT", 10),
    i("LCDT", 10),
    i("BEAM", 10),
    i("NPLTC", 10),
    i("PSETID", 10),
];
const D3B: &[F] = &[
    i("IOOPT", 10),
    r("RATE", 10),
    r("CUTOFF", 10),
    r("WINDOW", 10),
    i("TYPE", 10),
    i("PSET", 10),
];

fn d3plot(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    let row = c.need(D3, "DT")?;
    row.unsupported_all(&[
        (1, "an interval curve (LCDT)"),
        (2, "BEAM"),
        (4, "a part set (PSETID)"),
    ])?;
    if let Some(r2) = c.next(D3B)? {
        for k in 0..6 {
            r2.unsupported(k, "the second D3PLOT card")?;
        }
    }
    let npltc = row.int_or(3, 0)?;
    if npltc < 0 {
        return Err(row.err(3, format!("{npltc}: must be >= 0")));
    }
    deck.d3plot = Some((row.real_or(0, 0.0)?, npltc, row.loc));
    c.done()
}

const DB: &[F] = &[
    r("DT", 10),
    i("BINARY", 10),
    i("LCUR", 10),
    i("IOOPT", 10),
    r("DTHF", 10),
    i("BINHF", 10),
];

fn database(deck: &mut Deck, c: &mut Cards<'_>, db: Db) -> Result<(), DeckError> {
    let row = c.need(DB, "DT")?;
    let binary = row.int_or(1, 0)?;
    if !(0..=3).contains(&binary) {
        return Err(row.err(1, format!("{binary}: must be 0..3")));
    }
    row.unsupported_all(&[
        (2, "an interval curve (LCUR)"),
        (3, "IOOPT"),
        (4, "DTHF"),
        (5, "BINHF"),
    ])?;
    let dt = row.real_or(0, 0.0)?;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(row.err(0, format!("{dt}: the output interval must be > 0")));
    }
    deck.database.insert(db, (dt, row.loc));
    c.done()
}

fn history(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    while let Some(row) = c.next(LIST8)? {
        let mut list = Vec::new();
        ids(&row, &mut list)?;
        deck.history
            .extend(list.into_iter().map(|id| (id, row.loc)));
    }
    Ok(())
}
