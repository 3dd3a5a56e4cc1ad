//! Readers of sections, materials, node and part sets, and load curves.

use super::cards::{i, r, t, Row, F};
use super::deck::{Cards, Curve, Deck, Mat, MatKind, Section, Set};
use super::readers::{code_mask, insert_unique};
use super::DeckError;

#[rustfmt::skip]
const SEC1: &[F] = &[
    i("SECID", 10), i("ELFORM", 10), r("SHRF", 10), r("NIP", 10), r("PROPT", 10),
    r("QR/IRID", 10), i("ICOMP", 10), i("SETYP", 10)
];
#[rustfmt::skip]
const SEC2: &[F] = &[
    r("T1", 10), r("T2", 10), r("T3", 10), r("T4", 10), r("NLOC", 10), r("MAREA", 10),
    r("IDOF", 10), r("EDGSET", 10)
];

pub fn sections(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    while let Some(row) = c.next(SEC1)? {
        let id = row.id(0)?;
        let elform = row.int_or(1, 0)?;
        if (101..=105).contains(&elform) {
            return Err(row.err(
                1,
                format!("{elform}: user-defined elements are not supported"),
            ));
        }
        row.unsupported(6, "a composite section (ICOMP)")?;
        let setyp = row.int_or(7, 1)?;
        if setyp > 1 {
            return Err(row.err(
                7,
                format!("{setyp}: only 3D shells (SETYP 1) are supported"),
            ));
        }
        let shrf = row.real(2)?.filter(|&v| v != 0.0);
        let th = c.need(SEC2, "T1 ... T4")?;
        let t1 = th.real_or(0, 0.0)?;
        for k in 1..4 {
            let tk = th.real_or(k, 0.0)?;
            if tk != 0.0 && tk != t1 {
                return Err(th.err(
                    k,
                    format!("{tk} differs from T1 = {t1}: a varying thickness is not supported"),
                ));
            }
        }
        th.unsupported_all(&[
            (4, "a reference-surface offset (NLOC)"),
            (5, "non-structural mass (MAREA)"),
            (6, "IDOF"),
            (7, "EDGSET"),
        ])?;
        if elform != 0 && elform != 2 {
            deck.notes.push(format!(
                "{}:{}: *SECTION_SHELL {id}: ELFORM {elform} is run as crash's own shell element (Reissner-Mindlin, docs/theory.md)",
                c.lx.file(row.loc),
                row.loc.line
            ));
        }
        let s = Section {
            id,
            elform,
            shrf,
            thickness: t1,
            loc: row.loc,
        };
        insert_unique(c.lx, &mut deck.sections, id, s, "SECTION_SHELL", "section")?;
    }
    Ok(())
}

#[rustfmt::skip]
const ELASTIC: &[F] = &[
    i("MID", 10), r("RO", 10), r("E", 10), r("PR", 10), r("DA", 10), r("DB", 10), r("K", 10)
];
#[rustfmt::skip]
const RIGID1: &[F] = &[
    i("MID", 10), r("RO", 10), r("E", 10), r("PR", 10), r("N", 10), r("COUPLE", 10),
    r("M", 10), t("ALIAS", 10)
];
#[rustfmt::skip]
const RIGID2: &[F] = &[
    r("CMO", 10), r("CON1", 10), r("CON2", 10), i("SPCNID", 10), r("XSPC", 10),
    r("YSPC", 10), r("ZSPC", 10)
];
#[rustfmt::skip]
const RIGID3: &[F] = &[
    r("LCO/A1", 10), r("A2", 10), r("A3", 10), r("V1", 10), r("V2", 10), r("V3", 10),
    i("BNDLCO", 10)
];

fn add_mat(deck: &mut Deck, c: &Cards<'_>, m: Mat) -> Result<(), DeckError> {
    insert_unique(c.lx, &mut deck.mats, m.id, m, &c.b.name, "material")?;
    c.done()
}

pub fn elastic(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    let row = c.need(ELASTIC, "MID RO E PR")?;
    row.unsupported_all(&[
        (4, "axial damping (DA, beams)"),
        (5, "bending damping (DB, beams)"),
        (6, "the bulk modulus of the fluid option (K)"),
    ])?;
    let m = Mat {
        id: row.id(0)?,
        ro: row.real_or(1, 0.0)?,
        e: row.real_or(2, 0.0)?,
        pr: row.real_or(3, 0.0)?,
        kind: MatKind::Elastic,
        keyword: c.b.name.clone(),
        loc: row.loc,
    };
    add_mat(deck, c, m)
}

pub fn rigid(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    let row = c.need(RIGID1, "MID RO E PR")?;
    row.unsupported_all(&[
        (4, "MADYMO coupling (N)"),
        (5, "COUPLE"),
        (6, "MADYMO coupling (M)"),
    ])?;
    if !row.text(7).is_empty() {
        return Err(row.err(7, "a VDA surface alias is not supported"));
    }
    let (mut cmo, mut con) = (0, 0u8);
    if let Some(r2) = c.next(RIGID2)? {
        cmo = r2.flag(0)?;
        if cmo != 0 && cmo != 1 {
            return Err(r2.err(
                0,
                format!("{cmo}: only 0 (none) and 1 (global constraints) are supported"),
            ));
        }
        for (k, shift) in [(1, 0), (2, 3)] {
            let code = r2.flag(k)?;
            let m = code_mask(code).ok_or_else(|| r2.err(k, format!("{code}: must be 0..7")))?;
            if cmo == 1 {
                con |= m << shift;
            } else if m != 0 {
                return Err(r2.err(k, "constraints need CMO = 1"));
            }
        }
        r2.unsupported_all(&[(3, "SPCNID"), (4, "XSPC"), (5, "YSPC"), (6, "ZSPC")])?;
    }
    if let Some(r3) = c.next(RIGID3)? {
        r3.unsupported_all(&[
            (0, "LCO / A1 (output directions)"),
            (1, "A2"),
            (2, "A3"),
            (3, "V1"),
            (4, "V2"),
            (5, "V3"),
            (6, "BNDLCO"),
        ])?;
    }
    let m = Mat {
        id: row.id(0)?,
        ro: row.real_or(1, 0.0)?,
        e: row.real_or(2, 0.0)?,
        pr: row.real_or(3, 0.0)?,
        kind: MatKind::Rigid { cmo, con },
        keyword: c.b.name.clone(),
        loc: row.loc,
    };
    add_mat(deck, c, m)
}

#[rustfmt::skip]
const SET1: &[F] = &[
    i("SID", 10), r("DA1", 10), r("DA2", 10), r("DA3", 10), r("DA4", 10), t("SOLVER", 10)
];
#[rustfmt::skip]
const IDS8: &[F] = &[
    i("ID1", 10), i("ID2", 10), i("ID3", 10), i("ID4", 10), i("ID5", 10), i("ID6", 10),
    i("ID7", 10), i("ID8", 10)
];

/// Up to eight ids of a list card (blank and 0 skipped).
pub fn ids(row: &Row<'_>, out: &mut Vec<i64>) -> Result<(), DeckError> {
    for k in 0..8 {
        match row.int(k)? {
            None | Some(0) => {}
            Some(v) if v > 0 => out.push(v),
            Some(v) => return Err(row.err(k, format!("{v}: ids are > 0"))),
        }
    }
    Ok(())
}

pub const LIST8: &[F] = IDS8;

pub fn set(deck: &mut Deck, c: &mut Cards<'_>, name: &str) -> Result<(), DeckError> {
    let head = c.need(SET1, "SID")?;
    let id = head.id(0)?;
    head.unsupported_all(&[(1, "DA1"), (2, "DA2"), (3, "DA3"), (4, "DA4")])?;
    let solver = head.text(5).to_ascii_uppercase();
    if !(solver.is_empty() || solver == "MECH") {
        return Err(head.err(
            5,
            format!("{solver}: only MECH (mechanics) sets are supported"),
        ));
    }
    let mut s = Set {
        id,
        items: Vec::new(),
        ranges: Vec::new(),
        keyword: c.b.name.clone(),
        loc: head.loc,
    };
    while let Some(row) = c.next(IDS8)? {
        if name.ends_with("_GENERATE") {
            for k in (0..8).step_by(2) {
                let (a, b) = (row.int_or(k, 0)?, row.int_or(k + 1, 0)?);
                if a == 0 && b == 0 {
                    continue;
                }
                if a <= 0 || b < a {
                    return Err(row.err(k, format!("block {a}..{b}: needs 0 < first <= last")));
                }
                s.ranges.push((a, b));
            }
        } else {
            ids(&row, &mut s.items)?;
        }
    }
    let (map, what) = match name {
        "SET_PART_LIST" => (&mut deck.part_sets, "part set"),
        "SET_SHELL_LIST" | "SET_SHELL_LIST_GENERATE" => (&mut deck.shell_sets, "shell set"),
        _ => (&mut deck.node_sets, "node set"),
    };
    insert_unique(c.lx, map, id, s, name, what)
}

#[rustfmt::skip]
const CURVE1: &[F] = &[
    i("LCID", 10), i("SIDR", 10), r("SFA", 10), r("SFO", 10), r("OFFA", 10), r("OFFO", 10),
    i("DATTYP", 10), i("LCINT", 10)
];
const POINT: &[F] = &[r("A1", 20), r("O1", 20)];

pub fn curve(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    let head = c.need(CURVE1, "LCID")?;
    let id = head.id(0)?;
    head.unsupported_all(&[(1, "dynamic relaxation (SIDR)"), (6, "DATTYP")])?;
    let sfa = Some(head.real_or(2, 0.0)?)
        .filter(|&v| v != 0.0)
        .unwrap_or(1.0);
    let sfo = Some(head.real_or(3, 0.0)?)
        .filter(|&v| v != 0.0)
        .unwrap_or(1.0);
    let (offa, offo) = (head.real_or(4, 0.0)?, head.real_or(5, 0.0)?);
    let mut points = Vec::new();
    while let Some(row) = c.next(POINT)? {
        if row.raw(0).is_empty() && row.raw(1).is_empty() {
            continue;
        }
        let (a, o) = (row.real_or(0, 0.0)?, row.real_or(1, 0.0)?);
        let p = (sfa * a + offa, sfo * o + offo);
        if let Some(&(prev, _)) = points.last() {
            if p.0 <= prev {
                return Err(row.err(
                    0,
                    format!(
                        "time {} is not after the previous point's {prev}: abscissas must increase",
                        p.0
                    ),
                ));
            }
        }
        points.push(p);
    }
    if points.is_empty() {
        return Err(head.card_err(format!("curve {id} has no points")));
    }
    let cv = Curve {
        id,
        points,
        loc: head.loc,
    };
    insert_unique(c.lx, &mut deck.curves, id, cv, "DEFINE_CURVE", "curve")
}
