//! A keyword deck as typed records, each with where it was written. `read` lexes the
//! deck and hands each block to its reader (`readers`); an unknown keyword or an
//! unsupported option of a known one stops with its file, line and name.

use super::cards::{split, Row, F};
use super::lexer::{lex, Block, Lexed, Loc};
use super::readers;
use super::DeckError;
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    pub id: i64,
    pub x: [f64; 3],
    /// DOFs held by the card's TC and RC (crash_core::body::dof bits).
    pub mask: u8,
    pub loc: Loc,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Shell {
    pub id: i64,
    pub part: i64,
    /// 3 (triangle) or 4 node ids.
    pub nodes: Vec<i64>,
    pub loc: Loc,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    pub id: i64,
    pub heading: String,
    pub secid: i64,
    pub mid: i64,
    pub loc: Loc,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    pub id: i64,
    pub elform: i64,
    /// SHRF when given (not blank or 0).
    pub shrf: Option<f64>,
    pub thickness: f64,
    pub loc: Loc,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MatKind {
    Elastic,
    /// CMO (0 or 1), CON1 and CON2 as DOF masks (translations, rotations).
    Rigid {
        cmo: i64,
        con: u8,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Mat {
    pub id: i64,
    pub ro: f64,
    pub e: f64,
    pub pr: f64,
    pub kind: MatKind,
    pub keyword: String,
    pub loc: Loc,
}

/// A node set (ids, and for _GENERATE inclusive ranges) or a part set.
#[derive(Debug, Clone, PartialEq)]
pub struct Set {
    pub id: i64,
    pub items: Vec<i64>,
    pub ranges: Vec<(i64, i64)>,
    pub keyword: String,
    pub loc: Loc,
}

/// What a boundary condition, load or initial condition acts on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    Node(i64),
    NodeSet(i64),
    Part(i64),
    PartSet(i64),
    /// Every node of the deck.
    All,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Spc {
    pub target: Target,
    pub mask: u8,
    pub keyword: String,
    pub loc: Loc,
}

/// A prescribed velocity (VAD = 0) or a nodal load on one DOF (1-3 translations, 5-7
/// rotations), scaled by a curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Driven {
    pub target: Target,
    pub dof: i64,
    /// Prescribed motion: 0 velocity, 2 displacement (loads: 0).
    pub vad: i64,
    pub lcid: i64,
    pub sf: f64,
    /// DEATH of a prescribed motion (None: never).
    pub death: Option<f64>,
    pub keyword: String,
    pub loc: Loc,
}

/// A pressure on shells (*LOAD_SHELL_ELEMENT, *LOAD_SHELL_SET): pressure SF scaled by
/// curve LCID, positive against the element normal.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellPressure {
    /// An element id, or a shell set id (`set`).
    pub id: i64,
    pub set: bool,
    pub lcid: i64,
    pub sf: f64,
    pub keyword: String,
    pub loc: Loc,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    pub id: i64,
    /// Scaled and offset (SFA, SFO, OFFA, OFFO applied).
    pub points: Vec<(f64, f64)>,
    pub loc: Loc,
}

/// Rigid initial motion: v + omega x (x - centre).
#[derive(Debug, Clone, PartialEq)]
pub struct InitialVelocity {
    pub target: Target,
    pub v: [f64; 3],
    pub omega: [f64; 3],
    pub centre: [f64; 3],
    pub keyword: String,
    pub loc: Loc,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    /// SINGLE_SURFACE (else SURFACE_TO_SURFACE).
    pub single: bool,
    /// Parts of each side (the second is empty for a single surface); None: all parts.
    pub a: Target,
    pub b: Option<Target>,
    pub fs: f64,
    pub fd: f64,
    /// VDC [% of critical].
    pub vdc: f64,
    /// DT, the death time (None: never).
    pub death: Option<f64>,
    pub keyword: String,
    pub loc: Loc,
}

/// *DATABASE_* files other than D3PLOT.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Db {
    Glstat,
    Matsum,
    Rcforc,
    Nodout,
    Spcforc,
}

impl Db {
    pub fn key(self) -> &'static str {
        match self {
            Db::Glstat => "glstat",
            Db::Matsum => "matsum",
            Db::Rcforc => "rcforc",
            Db::Nodout => "nodout",
            Db::Spcforc => "spcforc",
        }
    }
}

/// The whole deck.
#[derive(Debug, Clone, Default)]
pub struct Deck {
    pub lx: Lexed,
    pub title: Option<(String, Loc)>,
    pub nodes: Vec<Node>,
    pub shells: Vec<Shell>,
    pub parts: BTreeMap<i64, Part>,
    pub sections: BTreeMap<i64, Section>,
    pub mats: BTreeMap<i64, Mat>,
    pub node_sets: BTreeMap<i64, Set>,
    pub part_sets: BTreeMap<i64, Set>,
    pub shell_sets: BTreeMap<i64, Set>,
    pub curves: BTreeMap<i64, Curve>,
    pub spcs: Vec<Spc>,
    pub motions: Vec<Driven>,
    pub loads: Vec<Driven>,
    pub pressures: Vec<ShellPressure>,
    pub velocities: Vec<InitialVelocity>,
    pub contacts: Vec<Contact>,
    pub end_time: Option<(f64, Loc)>,
    pub tssfac: Option<(f64, Loc)>,
    /// D3PLOT: DT or, with NPLTC, ENDTIM / NPLTC (resolved in convert).
    pub d3plot: Option<(f64, i64, Loc)>,
    pub database: BTreeMap<Db, (f64, Loc)>,
    pub history: Vec<(i64, Loc)>,
    /// Things read and not used, for the user (e.g. the element formulation).
    pub notes: Vec<String>,
}

impl Deck {
    /// `file:line` of a location, for messages.
    pub fn at(&self, loc: Loc) -> String {
        format!("{}:{}", self.lx.file(loc), loc.line)
    }

    pub fn error(&self, loc: Loc, keyword: &str, message: String) -> DeckError {
        self.lx.error(loc, 0, keyword, message)
    }
}

/// The cards of a block, read one layout at a time.
#[derive(Debug)]
pub struct Cards<'a> {
    pub lx: &'a Lexed,
    pub b: &'a Block,
    at: usize,
}

impl<'a> Cards<'a> {
    pub fn new(lx: &'a Lexed, b: &'a Block) -> Self {
        Self { lx, b, at: 0 }
    }

    pub fn more(&self) -> bool {
        self.at < self.b.cards.len()
    }

    /// The next card (None when the block has no more).
    pub fn next(&mut self, layout: &'static [F]) -> Result<Option<Row<'a>>, DeckError> {
        let Some(c) = self.b.cards.get(self.at) else {
            return Ok(None);
        };
        self.at += 1;
        split(self.lx, self.b, c, layout).map(Some)
    }

    /// The next card, which the keyword requires.
    pub fn need(&mut self, layout: &'static [F], what: &str) -> Result<Row<'a>, DeckError> {
        self.next(layout)?.ok_or_else(|| {
            self.lx.error(
                self.b.loc,
                0,
                &self.b.name,
                format!("the {what} card is missing"),
            )
        })
    }

    /// No card may remain.
    pub fn done(&self) -> Result<(), DeckError> {
        match self.b.cards.get(self.at) {
            None => Ok(()),
            Some(c) => Err(self.lx.error(
                c.loc,
                0,
                &self.b.name,
                format!(
                    "unexpected card: *{} has {} card(s) here (optional cards and options are not supported)",
                    self.b.name, self.at
                ),
            )),
        }
    }
}

/// Read the deck at `path` (and its includes) into records.
pub fn read(path: &Path) -> Result<Deck, DeckError> {
    let lx = lex(path)?;
    let mut deck = Deck::default();
    for b in &lx.blocks {
        readers::block(&mut deck, &lx, b)?;
    }
    deck.lx = lx;
    Ok(deck)
}
