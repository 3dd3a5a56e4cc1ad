//! One reader per supported keyword: here the dispatch and the mesh (title, nodes,
//! shells, parts); `props` has sections, materials, sets and curves, `boundary` the
//! supports, prescribed motion, loads and initial velocities, `control` the contacts,
//! run controls and outputs. `block` dispatches and refuses everything else.

use super::cards::{i, r, t, F};
use super::deck::{Cards, Curve, Deck, Mat, Node, Part, Section, Set, Shell};
use super::lexer::{Block, Lexed, Loc};
use super::DeckError;
use super::{control, props};
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
    "SET_SHELL_LIST",
    "SET_SHELL_LIST_GENERATE",
    "BOUNDARY_SPC_NODE",
    "BOUNDARY_SPC_SET",
    "BOUNDARY_PRESCRIBED_MOTION_NODE",
    "BOUNDARY_PRESCRIBED_MOTION_SET",
    "BOUNDARY_PRESCRIBED_MOTION_RIGID",
    "LOAD_NODE_POINT",
    "LOAD_NODE_SET",
    "LOAD_SHELL_ELEMENT",
    "LOAD_SHELL_SET",
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
    "SET_SHELL_LIST",
    "SET_SHELL_LIST_GENERATE",
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
        "SECTION_SHELL" => props::sections(deck, &mut c),
        "MAT_ELASTIC" | "MAT_001" => props::elastic(deck, &mut c),
        "MAT_RIGID" | "MAT_020" => props::rigid(deck, &mut c),
        "SET_NODE_LIST"
        | "SET_NODE_LIST_GENERATE"
        | "SET_PART_LIST"
        | "SET_SHELL_LIST"
        | "SET_SHELL_LIST_GENERATE" => props::set(deck, &mut c, name),
        "DEFINE_CURVE" => props::curve(deck, &mut c),
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

#[rustfmt::skip]
const NODE: &[F] = &[i("NID", 8), r("X", 16), r("Y", 16), r("Z", 16), r("TC", 8), r("RC", 8)];

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

#[rustfmt::skip]
const SHELL: &[F] = &[
    i("EID", 8), i("PID", 8), i("N1", 8), i("N2", 8), i("N3", 8), i("N4", 8), i("N5", 8),
    i("N6", 8), i("N7", 8), i("N8", 8)
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

#[rustfmt::skip]
const PART2: &[F] = &[
    i("PID", 10), i("SECID", 10), i("MID", 10), i("EOSID", 10), i("HGID", 10), i("GRAV", 10),
    i("ADPOPT", 10), i("TMID", 10)
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
