//! Readers of contacts, run controls and outputs, and the dispatch of the keywords
//! that act on the model (`boundary` reads supports, prescribed motion, nodal loads
//! and initial velocities).

use super::boundary::{driven, generation, shell_pressure, spc, velocity, Kind};
use super::cards::{i, r, t, Row, F};
use super::deck::{Cards, Contact, Db, Deck, Target};
use super::props::{ids, LIST8};
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
        "LOAD_SHELL_ELEMENT" => shell_pressure(deck, c, false),
        "LOAD_SHELL_SET" => shell_pressure(deck, c, true),
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

const CID: &[F] = &[i("CID", 10), t("HEADING", 70)];
#[rustfmt::skip]
const C1: &[F] = &[
    i("SSID", 10), i("MSID", 10), i("SSTYP", 10), i("MSTYP", 10), i("SBOXID", 10),
    i("MBOXID", 10), i("SPR", 10), i("MPR", 10)
];
#[rustfmt::skip]
const C2: &[F] = &[
    r("FS", 10), r("FD", 10), r("DC", 10), r("VC", 10), r("VDC", 10), i("PENCHK", 10),
    r("BT", 10), r("DT", 10)
];
#[rustfmt::skip]
const C3: &[F] = &[
    r("SFS", 10), r("SFM", 10), r("SST", 10), r("MST", 10), r("SFST", 10), r("SFMT", 10),
    r("FSF", 10), r("VSF", 10)
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

#[rustfmt::skip]
const TERM: &[F] = &[
    r("ENDTIM", 10), i("ENDCYC", 10), r("DTMIN", 10), r("ENDENG", 10), r("ENDMAS", 10),
    i("NOSOL", 10)
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

#[rustfmt::skip]
const TS1: &[F] = &[
    r("DTINIT", 10), r("TSSFAC", 10), i("ISDO", 10), r("TSLIMT", 10), r("DT2MS", 10),
    i("LCTM", 10), i("ERODE", 10), i("MS1ST", 10)
];
#[rustfmt::skip]
const TS2: &[F] = &[
    r("DT2MSF", 10), i("DT2MSLC", 10), i("IMSCL", 10), r("UNUSED", 10), r("UNUSED", 10),
    r("RMSCL", 10), r("UNUSED", 10), i("IHDO", 10)
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

#[rustfmt::skip]
const D3: &[F] = &[r("DT", 10), i("LCDT", 10), i("BEAM", 10), i("NPLTC", 10), i("PSETID", 10)];
#[rustfmt::skip]
const D3B: &[F] = &[
    i("IOOPT", 10), r("RATE", 10), r("CUTOFF", 10), r("WINDOW", 10), i("TYPE", 10),
    i("PSET", 10)
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

#[rustfmt::skip]
const DB: &[F] = &[
    r("DT", 10), i("BINARY", 10), i("LCUR", 10), i("IOOPT", 10), r("DTHF", 10),
    i("BINHF", 10)
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
