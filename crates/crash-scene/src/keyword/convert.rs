//! From deck records to bodies: one body per *PART with its own mesh (nodes shared by
//! two parts are refused), sets resolved to nodes, supports, prescribed motion, loads
//! and initial velocities grouped per body, rigid parts made kinematic when fully
//! constrained. `emit` writes the result as a scene.

use super::deck::{Deck, InitialVelocity, MatKind, Target};
use super::lexer::Loc;
use super::{DeckError, DeckOptions};
use crate::msh::MshSurface;
use crash_core::body::dof;
use std::collections::{BTreeMap, BTreeSet, HashMap};

/// Which nodes of a body an entry picks.
#[derive(Debug, Clone, PartialEq)]
pub enum Sel {
    All,
    /// Node ids (deck ids), ascending.
    Ids(Vec<i64>),
}

/// A prescribed velocity: components and angular components scaled by `curve` (a deck
/// curve id) or, when several curves were combined as ramps, by a ramp of `ramp` s.
#[derive(Debug, Clone, PartialEq)]
pub struct Prescribe {
    pub sel: Sel,
    pub v: [f64; 3],
    pub w: [f64; 3],
    pub curve: Option<i64>,
    pub ramp: Option<f64>,
    /// `v` is a displacement [m] (VAD = 2), not a velocity.
    pub displacement: bool,
    pub loc: Loc,
    pub what: String,
}

#[derive(Debug, Clone, PartialEq)]
pub struct LoadOut {
    pub sel: Sel,
    pub force: Option<[f64; 3]>,
    pub moment: Option<[f64; 3]>,
    pub curve: i64,
    pub loc: Loc,
    pub what: String,
}

/// A pressure on a body's shells: `elements` (deck element ids, ascending) or all.
#[derive(Debug, Clone, PartialEq)]
pub struct PressureOut {
    pub elements: Option<Vec<i64>>,
    pub value: f64,
    pub curve: i64,
    pub loc: Loc,
    pub what: String,
}

#[derive(Debug, Clone, PartialEq)]
pub struct BodyOut {
    pub pid: i64,
    pub name: String,
    pub loc: Loc,
    pub mid: i64,
    pub secid: i64,
    pub surface: MshSurface,
    /// File index of each element (Mesh order), for `MeshSource::written`.
    pub element_files: Vec<u32>,
    pub fixes: Vec<(Sel, u8, Loc, String)>,
    pub prescribes: Vec<Prescribe>,
    pub loads: Vec<LoadOut>,
    pub pressures: Vec<PressureOut>,
    pub velocity: Option<InitialVelocity>,
    pub contact: bool,
    pub self_contact: bool,
}

/// The deck as bodies and the scene-wide values.
#[derive(Debug, Clone, Default)]
pub struct Model {
    pub bodies: Vec<BodyOut>,
    /// (end time, where).
    pub end_time: (f64, Loc),
    pub output_interval: Option<(f64, Loc)>,
    pub contact: Option<ContactOut>,
    /// Node histories: body index, node ids, where.
    pub history: Vec<(usize, Vec<i64>, Loc)>,
    pub notes: Vec<String>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ContactOut {
    pub damping_ratio: f64,
    pub loc: Loc,
}

pub(super) struct Index<'a> {
    pub deck: &'a Deck,
    /// Node id -> index in deck.nodes.
    pub node: HashMap<i64, usize>,
    /// Per deck node: (body, local index) once used by an element.
    pub owner: Vec<Option<(usize, u32)>>,
    /// Part id -> body index.
    pub body_of: BTreeMap<i64, usize>,
}

impl Index<'_> {
    pub fn err(&self, loc: Loc, kw: &str, message: String) -> DeckError {
        self.deck.error(loc, kw, message)
    }

    /// Deck node indices of a target, each in a body (a node of no element is refused).
    pub fn nodes(&self, t: Target, loc: Loc, kw: &str) -> Result<Vec<usize>, DeckError> {
        let d = self.deck;
        let mut out = Vec::new();
        match t {
            Target::Node(id) => out.push(self.node_index(id, loc, kw, "")?),
            Target::NodeSet(sid) => {
                let s = d.node_sets.get(&sid).ok_or_else(|| {
                    self.err(
                        loc,
                        kw,
                        format!("node set {sid} is not defined (*SET_NODE_LIST)"),
                    )
                })?;
                let from = format!(" (node set {sid} at {})", d.at(s.loc));
                for &id in &s.items {
                    out.push(self.node_index(id, s.loc, &s.keyword, &from)?);
                }
                for (k, n) in d.nodes.iter().enumerate() {
                    if s.ranges.iter().any(|&(a, b)| (a..=b).contains(&n.id)) {
                        out.push(k);
                    }
                }
            }
            Target::Part(_) | Target::PartSet(_) | Target::All => {
                let bodies = self.bodies(t, loc, kw)?;
                for (k, o) in self.owner.iter().enumerate() {
                    if o.is_some_and(|(b, _)| bodies.contains(&b)) {
                        out.push(k);
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        for &k in &out {
            if self.owner[k].is_none() {
                let n = &d.nodes[k];
                return Err(self.err(loc, kw, format!(
                    "node {} (*NODE at {}) belongs to no shell element: crash has no free nodes (it would have no mass)",
                    n.id, d.at(n.loc)
                )));
            }
        }
        Ok(out)
    }

    fn node_index(&self, id: i64, loc: Loc, kw: &str, from: &str) -> Result<usize, DeckError> {
        self.node
            .get(&id)
            .copied()
            .ok_or_else(|| self.err(loc, kw, format!("node {id}{from} is not defined (*NODE)")))
    }

    /// Body indices of a part target.
    pub fn bodies(&self, t: Target, loc: Loc, kw: &str) -> Result<BTreeSet<usize>, DeckError> {
        let part = |pid: i64| {
            self.body_of.get(&pid).copied().ok_or_else(|| {
                self.err(
                    loc,
                    kw,
                    format!("part {pid} is not defined (*PART with elements)"),
                )
            })
        };
        Ok(match t {
            Target::Part(pid) => [part(pid)?].into(),
            Target::PartSet(sid) => {
                let s = self.deck.part_sets.get(&sid).ok_or_else(|| {
                    self.err(
                        loc,
                        kw,
                        format!("part set {sid} is not defined (*SET_PART_LIST)"),
                    )
                })?;
                s.items.iter().map(|&p| part(p)).collect::<Result<_, _>>()?
            }
            Target::All => (0..self.body_of.len()).collect(),
            _ => BTreeSet::new(),
        })
    }
}

/// Group node indices by body: body -> node ids (ascending by deck order).
pub(super) fn by_body(ix: &Index<'_>, nodes: &[usize]) -> BTreeMap<usize, Vec<i64>> {
    let mut out: BTreeMap<usize, Vec<i64>> = BTreeMap::new();
    for &k in nodes {
        if let Some((b, _)) = ix.owner[k] {
            out.entry(b).or_default().push(ix.deck.nodes[k].id);
        }
    }
    out
}

/// `Sel::All` when `ids` are every node of the body.
pub(super) fn sel(ids: Vec<i64>, body: &BodyOut) -> Sel {
    if ids.len() == body.surface.node_tags.len() {
        Sel::All
    } else {
        let mut ids = ids;
        ids.sort_unstable();
        Sel::Ids(ids)
    }
}

/// The bodies: meshes, materials, sections; nodes owned by exactly one part.
pub fn model(deck: &Deck, opts: &DeckOptions) -> Result<Model, DeckError> {
    let mut node = HashMap::with_capacity(deck.nodes.len());
    for (k, n) in deck.nodes.iter().enumerate() {
        if let Some(old) = node.insert(n.id, k) {
            return Err(deck.error(
                n.loc,
                "NODE",
                format!(
                    "node {} is defined twice (first at {})",
                    n.id,
                    deck.at(deck.nodes[old].loc)
                ),
            ));
        }
    }
    let end_time = deck.end_time.ok_or_else(|| DeckError {
        file: deck.lx.files.first().cloned().unwrap_or_default(),
        line: 0,
        column: 0,
        keyword: "CONTROL_TERMINATION".into(),
        message: "the deck has no *CONTROL_TERMINATION: its end time (ENDTIM) is required".into(),
    })?;
    let mut ix = Index {
        deck,
        node,
        owner: vec![None; deck.nodes.len()],
        body_of: BTreeMap::new(),
    };
    let bodies = super::mesh::bodies(&mut ix)?;
    let mut m = Model {
        bodies,
        end_time,
        ..Model::default()
    };
    let orphans: Vec<i64> = (0..deck.nodes.len())
        .filter(|&k| ix.owner[k].is_none())
        .map(|k| deck.nodes[k].id)
        .collect();
    if let Some(first) = orphans.first() {
        m.notes.push(format!(
            "{} node(s) of the deck belong to no shell element and are not part of any body (node {first}{})",
            orphans.len(),
            if orphans.len() > 1 { ", ..." } else { "" }
        ));
    }
    super::bc::supports_and_motion(&ix, &mut m)?;
    super::bc::loads(&ix, &mut m)?;
    super::bc::pressures(&ix, &mut m)?;
    velocities(&ix, &mut m)?;
    super::bc::contacts(&ix, &mut m, opts)?;
    outputs(&ix, &mut m)?;
    m.notes.extend(deck.notes.iter().cloned());
    Ok(m)
}

fn velocities(ix: &Index<'_>, m: &mut Model) -> Result<(), DeckError> {
    for v in &ix.deck.velocities {
        let nodes = ix.nodes(v.target, v.loc, &v.keyword)?;
        for (b, ids) in by_body(ix, &nodes) {
            let body = &mut m.bodies[b];
            if ids.len() != body.surface.node_tags.len() {
                return Err(ix.err(v.loc, &v.keyword, format!(
                    "covers {} of the {} nodes of part {}: an initial velocity must cover whole parts (crash gives a body one rigid initial motion)",
                    ids.len(), body.surface.node_tags.len(), body.pid
                )));
            }
            if rigid(ix, body).is_some() && (v.v != [0.0; 3] || v.omega != [0.0; 3]) {
                return Err(ix.err(v.loc, &v.keyword, format!(
                    "part {} is rigid and fully constrained (kinematic in crash): give its motion with *BOUNDARY_PRESCRIBED_MOTION_RIGID, not an initial velocity",
                    body.pid
                )));
            }
            if let Some(old) = &body.velocity {
                if (old.v, old.omega, old.centre) != (v.v, v.omega, v.centre) {
                    return Err(ix.err(
                        v.loc,
                        &v.keyword,
                        format!(
                            "part {} already has another initial velocity (at {})",
                            body.pid,
                            ix.deck.at(old.loc)
                        ),
                    ));
                }
            }
            body.velocity = Some(v.clone());
        }
    }
    Ok(())
}

fn outputs(ix: &Index<'_>, m: &mut Model) -> Result<(), DeckError> {
    let d = ix.deck;
    if let Some((dt, npltc, loc)) = d.d3plot {
        let interval = if dt > 0.0 {
            dt
        } else if npltc > 0 {
            m.end_time.0 / npltc as f64
        } else {
            return Err(ix.err(
                loc,
                "DATABASE_BINARY_D3PLOT",
                "DT: the interval must be > 0 (or NPLTC > 0)".into(),
            ));
        };
        m.output_interval = Some((interval, loc));
    }
    let mut per_body: BTreeMap<usize, (Vec<i64>, Loc)> = BTreeMap::new();
    for &(id, loc) in &d.history {
        let k = ix.nodes(Target::Node(id), loc, "DATABASE_HISTORY_NODE")?;
        if let Some((b, _)) = ix.owner[k[0]] {
            per_body
                .entry(b)
                .or_insert_with(|| (Vec::new(), loc))
                .0
                .push(id);
        }
    }
    m.history = per_body
        .into_iter()
        .map(|(b, (ids, loc))| (b, ids, loc))
        .collect();
    Ok(())
}

/// Names of the DOFs in a mask, for messages.
pub fn dof_names(mask: u8) -> String {
    ["x", "y", "z", "rx", "ry", "rz"]
        .iter()
        .enumerate()
        .filter(|(k, _)| mask & (1 << k) != 0)
        .map(|(_, n)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}

/// DOF bit of an LS-DYNA DOF number (1-3, 5-7).
pub fn dof_bit(d: i64) -> u8 {
    match d {
        1..=3 => 1 << (d - 1),
        5..=7 => 1 << (d - 2),
        _ => 0,
    }
}

/// The unit vector of a translational or rotational DOF (its index 0..3 and whether it
/// is a rotation).
pub fn dof_axis(d: i64) -> (usize, bool) {
    if d <= 3 {
        ((d - 1) as usize, false)
    } else {
        ((d - 5) as usize, true)
    }
}

/// Every DOF.
pub const ALL: u8 = dof::ALL;

/// The constrained DOFs of a rigid (*MAT_RIGID) body; None for a deformable one.
pub(super) fn rigid(ix: &Index<'_>, body: &BodyOut) -> Option<u8> {
    match ix.deck.mats.get(&body.mid).map(|m| m.kind) {
        Some(MatKind::Rigid { con, .. }) => Some(con),
        _ => None,
    }
}
