//! One reader per supported keyword (model part: nodes, shells, parts, sections,
//! materials, sets, curves, title); `control` has the boundary conditions, loads,
//! initial velocities, contacts, controls and outputs. `block` dispatches and refuses
//! everything else.

use super::cards::{i, r, t, F};
use super::control;
use super::deck::{Cards, Curve, Deck, Mat, MatKind, Node, Part, Section, Set, Shell};
use super::lexer::{Block, Lexed, Loc};
use super::DeckError;
use std::collections::BTreeMap;

/// Every supported keyword, for the message about an unsupported one.
pub const SUPPORTED: &[&str] = &[
    "KEYWORD",
    "TITLE",
    "INCLUDE",
    "END",
    "NODE",
    "ELEMENT_SHELL",
    "PART",
    "SECTION_SHELL",
    "MAT_ELASTIC",
    "MAT_001",
    "MAT_RIGID",
    "MAT_020",
    "SET_NODE_LIST",
    "SET_NODE_LIST_GENERATE",
    "SET_PART_LIST",
    "BOUNDARY_SPC_NODE",
    "BOUNDARY_SPC_SET",
    "BOUNDARY_PRESCRIBED_MOTION_NODE",
    "BOUNDARY_PRESCRIBED_MOTION_SET",
    "BOUNDARY_PRESCRIBED_MOTION_RIGID",
    "LOAD_NODE_POINT",
    "LOAD_NODE_SET",
    "DEFINE_CURVE",
    "INITIAL_VELOCITY",
    "INITIAL_VELOCITY_GENERATION",
    "CONTACT_AUTOMATIC_SINGLE_SURFACE",
    "CONTACT_AUTOMATIC_SURFACE_TO_SURFACE",
    "CONTROL_TERMINATION",
    "CONTROL_TIMESTEP",
    "DATABASE_BINARY_D3PLOT",
    "DATABASE_GLSTAT",
    "DATABASE_MATSUM",
    "DATABASE_RCFORC",
    "DATABASE_NODOUT",
    "DATABASE_SPCFORC",
    "DATABASE_HISTORY_NODE",
];

/// Keywords that take a `_TITLE` option (a title card first).
const TITLED: &[&str] = &[
    "SECTION_SHELL",
    "MAT_ELASTIC",
    "MAT_001",
    "MAT_RIGID",
    "MAT_020",
    "SET_NODE_LIST",
    "SET_NODE_LIST_GENERATE",
    "SET_PART_LIST",
    "DEFINE_CURVE",
];

pub const TITLE: &[F] = &[t("TITLE", 80)];

/// Read one block into the deck.
pub fn block(deck: &mut Deck, lx: &Lexed, b: &Block) -> Result<(), DeckError> {
    let mut name = b.name.as_str();
    let mut c = Cards::new(lx, b);
    if let Some(base) = name.strip_suffix("_TITLE") {
        if TITLED.contains(&base) {
            c.need(TITLE, "title")?;
            name = base;
        }
    }
    match name {
        "KEYWORD" | "END" => c.done(),
        "TITLE" => {
            let row = c.need(TITLE, "title")?;
            deck.title = Some((row.text(0).to_string(), row.loc));
            c.done()
        }
        "NODE" => nodes(deck, &mut c),
        "ELEMENT_SHELL" => shells(deck, &mut c),
        "PART" => parts(deck, &mut c),
        "SECTION_SHELL" => sections(deck, &mut c),
        "MAT_ELASTIC" | "MAT_001" => elastic(deck, &mut c),
        "MAT_RIGID" | "MAT_020" => rigid(deck, &mut c),
        "SET_NODE_LIST" | "SET_NODE_LIST_GENERATE" | "SET_PART_LIST" => set(deck, &mut c, name),
        "DEFINE_CURVE" => curve(deck, &mut c),
        _ => control::block(deck, &mut c, name).unwrap_or_else(|| Err(unsupported(lx, b))),
    }
}

/// The error for a keyword this reader does not know: names the option when the
/// keyword is a supported one with an option added.
fn unsupported(lx: &Lexed, b: &Block) -> DeckError {
    let base = SUPPORTED
        .iter()
        .filter(|k| b.name.starts_with(&format!("{k}_")))
        .max_by_key(|k| k.len());
    let message = match base {
        Some(k) => format!(
            "option {} of *{k} is not supported (docs/keyword-input.md lists what is)",
            &b.name[k.len()..]
        ),
        None => format!(
            "*{} is not supported: nothing is dropped silently, so the deck is refused (docs/keyword-input.md lists the supported keywords)",
            b.name
        ),
    };
    lx.error(b.loc, 0, &b.name, message)
}

/// Records with an id defined once per deck.
pub trait Located {
    fn loc(&self) -> Loc;
}

macro_rules! located {
    ($($t:ty),*) => {$(impl Located for $t { fn loc(&self) -> Loc { self.loc } })*};
}
located!(Part, Section, Mat, Set, Curve);

/// Insert `v` under `id` unless that id exists (then name both cards).
pub fn insert_unique<T: Located>(
    lx: &Lexed,
    map: &mut BTreeMap<i64, T>,
    id: i64,
    v: T,
    kw: &str,
    what: &str,
) -> Result<(), DeckError> {
    if let Some(old) = map.get(&id) {
        let o = old.loc();
        return Err(lx.error(
            v.loc(),
            0,
            kw,
            format!(
                "{what} {id} is defined twice (first at {}:{})",
                lx.file(o),
                o.line
            ),
        ));
    }
    map.insert(id, v);
    Ok(())
}

/// TC / RC codes of *NODE and CON1 / CON2 of *MAT_RIGID: 0 none, 1 x, 2 y, 3 z, 4 xy,
/// 5 yz, 6 zx, 7 xyz, as bits x = 1, y = 2, z = 4.
pub fn code_mask(code: i64) -> Option<u8> {
    Some(match code {
        0 => 0,
        1 => 1,
        2 => 2,
        3 => 4,
        4 => 3,
        5 => 6,
        6 => 5,
        7 => 7,
        _ => return None,
    })
}

const NODE: &[F] = &[
    i("NID", 8),
    r("X", 16),
    r("Y", 16),
    r("Z", 16),
    r("TC", 8),
    r("RC", 8),
];

fn nodes(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    while let Some(row) = c.next(NODE)? {
        if row.raw(0).is_empty() && row.raw(1).is_empty() {
            continue; // a blank line
        }
        let mut mask = 0;
        for (k, shift) in [(4, 0), (5, 3)] {
            let code = row.flag(k)?;
            mask |= code_mask(code).ok_or_else(|| {
                row.err(k, format!("{code}: must be 0..7 (0 none, 1 x, ..., 7 xyz)"))
            })? << shift;
        }
        deck.nodes.push(Node {
            id: row.id(0)?,
            x: [
                row.real_or(1, 0.0)?,
                row.real_or(2, 0.0)?,
                row.real_or(3, 0.0)?,
            ],
            mask,
            loc: row.loc,
        });
    }
    Ok(())
}

const SHELL: &[F] = &[
    i("EID", 8),
    i("PID", 8),
    i("N1", 8),
    i("N2", 8),
    i("N3", 8),
    i("N4", 8),
    i("N5", 8),
    i("N6", 8),
    i("N7", 8),
    i("N8", 8),
];

fn shells(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    while let Some(row) = c.next(SHELL)? {
        if (0..10).all(|k| row.raw(k).is_empty()) {
            continue;
        }
        let mut n = vec![row.id(2)?, row.id(3)?, row.id(4)?];
        let n4 = row.int_or(5, 0)?;
        if n4 < 0 {
            return Err(row.err(5, format!("{n4}: a node id must be > 0 (or blank)")));
        }
        if n4 != 0 && n4 != n[2] {
            n.push(n4);
        }
        for k in 6..10 {
            row.unsupported(k, "a higher-order shell node")?;
        }
        deck.shells.push(Shell {
            id: row.id(0)?,
            part: row.id(1)?,
            nodes: n,
            loc: row.loc,
        });
    }
    Ok(())
}

const PART2: &[F] = &[
    i("PID", 10),
    i("SECID", 10),
    i("MID", 10),
    i("EOSID", 10),
    i("HGID", 10),
    i("GRAV", 10),
    i("ADPOPT", 10),
    i("TMID", 10),
];

fn parts(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
    while let Some(head) = c.next(TITLE)? {
        let row = c.need(PART2, "PID SECID MID")?;
        row.unsupported_all(&[
            (3, "an equation of state"),
            (
                4,
                "an *HOURGLASS control (crash uses its own stabilization)",
            ),
            (5, "gravity initialisation"),
            (6, "adaptive meshing"),
            (7, "a thermal material"),
        ])?;
        let p = Part {
            id: row.id(0)?,
            heading: head.text(0).to_string(),
            secid: row.id(1)?,
            mid: row.id(2)?,
            loc: row.loc,
        };
        insert_unique(c.lx, &mut deck.parts, p.id, p, "PART", "part")?;
    }
    Ok(())
}

const SEC1: &[F] = &[
    i("SECID", 10),
    i("ELFORM", 10),
    r("SHRF", 10),
    r("NIP", 10),
    r("PROPT", 10),
    r("QR/IRID", 10),
    i("ICOMP", 10),
    i("SETYP", 10),
];
const SEC2: &[F] = &[
    r("T1", 10),
    r("T2", 10),
    r("T3", 10),
    r("T4", 10),
    r("NLOC", 10),
    r("MAREA", 10),
    r("IDOF", 10),
    r("EDGSET", 10),
];

fn sections(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
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

const ELASTIC: &[F] = &[
    i("MID", 10),
    r("RO", 10),
    r("E", 10),
    r("PR", 10),
    r("DA", 10),
    r("DB", 10),
    r("K", 10),
];
const RIGID1: &[F] = &[
    i("MID", 10),
    r("RO", 10),
    r("E", 10),
    r("PR", 10),
    r("N", 10),
    r("COUPLE", 10),
    r("M", 10),
    t("ALIAS", 10),
];
const RIGID2: &[F] = &[
    r("CMO", 10),
    r("CON1", 10),
    r("CON2", 10),
    i("SPCNID", 10),
    r("XSPC", 10),
    r("YSPC", 10),
    r("ZSPC", 10),
];
const RIGID3: &[F] = &[
    r("LCO/A1", 10),
    r("A2", 10),
    r("A3", 10),
    r("V1", 10),
    r("V2", 10),
    r("V3", 10),
    i("BNDLCO", 10),
];

fn add_mat(deck: &mut Deck, c: &Cards<'_>, m: Mat) -> Result<(), DeckError> {
    insert_unique(c.lx, &mut deck.mats, m.id, m, &c.b.name, "material")?;
    c.done()
}

fn elastic(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
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

fn rigid(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
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

const SET1: &[F] = &[
    i("SID", 10),
    r("DA1", 10),
    r("DA2", 10),
    r("DA3", 10),
    r("DA4", 10),
    t("SOLVER", 10),
];
const IDS8: &[F] = &[
    i("ID1", 10),
    i("ID2", 10),
    i("ID3", 10),
    i("ID4", 10),
    i("ID5", 10),
    i("ID6", 10),
    i("ID7", 10),
    i("ID8", 10),
];

/// Up to eight ids of a list card (blank and 0 skipped).
pub fn ids(row: &super::cards::Row<'_>, out: &mut Vec<i64>) -> Result<(), DeckError> {
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

fn set(deck: &mut Deck, c: &mut Cards<'_>, name: &str) -> Result<(), DeckError> {
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
        if name == "SET_NODE_LIST_GENERATE" {
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
    let (map, what) = if name == "SET_PART_LIST" {
        (&mut deck.part_sets, "part set")
    } else {
        (&mut deck.node_sets, "node set")
    };
    insert_unique(c.lx, map, id, s, name, what)
}

const CURVE1: &[F] = &[
    i("LCID", 10),
    i("SIDR", 10),
    r("SFA", 10),
    r("SFO", 10),
    r("OFFA", 10),
    r("OFFO", 10),
    i("DATTYP", 10),
    i("LCINT", 10),
];
const POINT: &[F] = &[r("A1", 20), r("O1", 20)];

fn curve(deck: &mut Deck, c: &mut Cards<'_>) -> Result<(), DeckError> {
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
