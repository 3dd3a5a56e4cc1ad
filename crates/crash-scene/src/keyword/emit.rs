//! A converted deck written as a scene: the TOML text (with a comment naming the card
//! of each entry), one Gmsh mesh per body, and the origin of every key so that scene
//! errors point at the deck's cards.

use super::convert::{Model, Sel};
use super::deck::Deck;
use super::lexer::Loc;
use crate::context::{Origin, Origins};
use crate::msh::MshSurface;
use std::fmt::Write;

/// A deck as a scene: what `crash convert` writes, what `crash run deck.k` parses.
#[derive(Debug, Clone)]
pub struct Converted {
    pub toml: String,
    /// Mesh file name (as the TOML names it), surface, and per element the index of
    /// the deck file it was written in (`files`).
    pub meshes: Vec<(String, MshSurface, Vec<u32>)>,
    /// The deck and its includes, as named in messages.
    pub files: Vec<String>,
    pub origins: Origins,
    pub notes: Vec<String>,
}

struct Out<'a> {
    deck: &'a Deck,
    text: String,
    origins: Origins,
}

impl Out<'_> {
    fn origin(&mut self, key: &str, loc: Loc, what: &str) {
        self.origins.insert(
            key.to_string(),
            Origin {
                file: self.deck.lx.file(loc).to_string(),
                line: loc.line,
                what: what.to_string(),
            },
        );
    }

    /// `# *KEYWORD at file:line` comment.
    fn at(&self, what: &str, loc: Loc) -> String {
        format!("# {what} at {}", self.deck.at(loc))
    }

    fn line(&mut self, s: impl AsRef<str>) {
        self.text.push_str(s.as_ref());
        self.text.push('\n');
    }
}

fn q(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

fn v3(x: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", x[0], x[1], x[2])
}

fn dofs(mask: u8) -> String {
    match mask {
        63 => q("all"),
        7 => q("translations"),
        56 => q("rotations"),
        m => {
            let names = ["x", "y", "z", "rx", "ry", "rz"];
            let list: Vec<String> = (0..6)
                .filter(|k| m & (1 << k) != 0)
                .map(|k| q(names[k]))
                .collect();
            format!("[{}]", list.join(", "))
        }
    }
}

fn select(o: &mut Out<'_>, s: &Sel) {
    match s {
        Sel::All => o.line("select = \"all\""),
        Sel::Ids(ids) => o.line(format!("select.nodes = [{}]", id_list(ids))),
    }
}

fn id_list(ids: &[i64]) -> String {
    let mut s = String::new();
    for (k, id) in ids.iter().enumerate() {
        if k % 10 == 0 {
            s.push_str("\n  ");
        } else {
            s.push(' ');
        }
        let _ = write!(s, "{id},");
    }
    s.push('\n');
    s
}

/// The scene text of a model; meshes are named `{mesh_prefix}.part{PID}.msh`.
pub fn emit(deck: &Deck, m: Model, name: &str, mesh_prefix: &str) -> Converted {
    let mut o = Out {
        deck,
        text: String::new(),
        origins: Origins::new(),
    };
    o.line(format!(
        "# Converted from the keyword deck {} by crash (docs/keyword-input.md).",
        deck.lx.files.first().map_or("", String::as_str)
    ));
    if let Some((t, loc)) = &deck.title {
        o.line(format!("# *TITLE {t}  ({})", deck.at(*loc)));
    }
    o.line(format!("name = {}", q(name)));
    let (end, loc) = m.end_time;
    o.line(format!(
        "end_time = {end:?}  {}",
        o.at("*CONTROL_TERMINATION", loc)
    ));
    o.origin("end_time", loc, "*CONTROL_TERMINATION (ENDTIM)");
    if let Some((s, loc)) = deck.tssfac {
        o.line(format!(
            "dt_safety = {s:?}  {}",
            o.at("*CONTROL_TIMESTEP", loc)
        ));
        o.origin("dt_safety", loc, "*CONTROL_TIMESTEP (TSSFAC)");
    }
    if let Some((dt, loc)) = m.output_interval {
        o.line(format!(
            "output_interval = {dt:?}  {}",
            o.at("*DATABASE_BINARY_D3PLOT", loc)
        ));
        o.origin("output_interval", loc, "*DATABASE_BINARY_D3PLOT");
    }
    o.line("");
    o.line("[contact]");
    match &m.contact {
        None => o.line("enabled = false  # the deck has no *CONTACT"),
        Some(c) => {
            o.line(format!("enabled = true  {}", o.at("*CONTACT", c.loc)));
            o.line(format!("damping_ratio = {:?}", c.damping_ratio));
            o.origin("contact", c.loc, "*CONTACT");
        }
    }
    if !deck.database.is_empty() || !m.history.is_empty() {
        o.line("");
        o.line("[outputs]  # requested; not written by the run yet (docs/keyword-input.md)");
        for (db, (dt, loc)) in &deck.database {
            let kw = format!("*DATABASE_{}", db.key().to_ascii_uppercase());
            o.line(format!("{} = {dt:?}  {}", db.key(), o.at(&kw, *loc)));
            o.origin(&format!("outputs.{}", db.key()), *loc, &kw);
        }
        for (k, (b, ids, loc)) in m.history.iter().enumerate() {
            o.line("");
            o.line(format!(
                "[[outputs.history]]  {}",
                o.at("*DATABASE_HISTORY_NODE", *loc)
            ));
            o.line(format!("body = {}", q(&m.bodies[*b].name)));
            o.line(format!("nodes = [{}]", id_list(ids)));
            o.origin(
                &format!("outputs.history[{k}]"),
                *loc,
                "*DATABASE_HISTORY_NODE",
            );
        }
    }
    let used_curves: std::collections::BTreeSet<i64> = m
        .bodies
        .iter()
        .flat_map(|b| {
            b.prescribes
                .iter()
                .filter_map(|p| p.curve)
                .chain(b.loads.iter().map(|l| l.curve))
                .chain(b.pressures.iter().map(|p| p.curve))
        })
        .collect();
    for c in deck.curves.values() {
        o.line("");
        let used = if used_curves.contains(&c.id) {
            ""
        } else {
            " (not used)"
        };
        o.line(format!(
            "[curves.lc{}]  {}{used}",
            c.id,
            o.at(&format!("*DEFINE_CURVE {}", c.id), c.loc)
        ));
        let pts: Vec<String> = c
            .points
            .iter()
            .map(|p| format!("[{:?}, {:?}]", p.0, p.1))
            .collect();
        o.line(format!("points = [{}]", pts.join(", ")));
        o.origin(
            &format!("curves.lc{}", c.id),
            c.loc,
            &format!("*DEFINE_CURVE {}", c.id),
        );
    }
    let used_mats: std::collections::BTreeSet<i64> = m.bodies.iter().map(|b| b.mid).collect();
    for mid in used_mats {
        let mat = &deck.mats[&mid];
        let what = format!("*{} {mid}", mat.keyword);
        o.line("");
        o.line(format!("[materials.mat{mid}]  {}", o.at(&what, mat.loc)));
        o.line(format!("density = {:?}", mat.ro));
        o.line(format!("young = {:?}", mat.e));
        o.line(format!("poisson = {:?}", mat.pr));
        o.origin(&format!("materials.mat{mid}"), mat.loc, &what);
    }
    let mut meshes = Vec::new();
    for (i, b) in m.bodies.into_iter().enumerate() {
        let key = format!("bodies[{i}]");
        let sec = &deck.sections[&b.secid];
        let pw = format!("*PART {}", b.pid);
        o.line("");
        o.line(format!("[[bodies]]  {}", o.at(&pw, b.loc)));
        o.origin(&key, b.loc, &pw);
        o.line(format!("name = {}", q(&b.name)));
        o.line(format!("material = {}", q(&format!("mat{}", b.mid))));
        let sw = format!("*SECTION_SHELL {}", b.secid);
        o.line(format!(
            "thickness = {:?}  {}",
            sec.thickness,
            o.at(&sw, sec.loc)
        ));
        o.origin(&format!("{key}.thickness"), sec.loc, &format!("{sw} (T1)"));
        if let Some(k) = sec.shrf {
            o.line(format!("shear_factor = {k:?}"));
            o.origin(
                &format!("{key}.shear_factor"),
                sec.loc,
                &format!("{sw} (SHRF)"),
            );
        }
        let file = format!("{mesh_prefix}.part{}.msh", b.pid);
        o.line(format!("mesh = {{ file = {} }}", q(&file)));
        o.line(format!("contact = {}", b.contact));
        o.line(format!("self_contact = {}", b.self_contact));
        if let Some(v) = &b.velocity {
            let what = format!("*{}", v.keyword);
            o.line(format!("velocity = {}  {}", v3(v.v), o.at(&what, v.loc)));
            for k in ["velocity", "angular_velocity", "angular_velocity_centre"] {
                o.origin(&format!("{key}.{k}"), v.loc, &what);
            }
            if v.omega != [0.0; 3] {
                o.line(format!("angular_velocity = {}", v3(v.omega)));
                o.line(format!("angular_velocity_centre = {}", v3(v.centre)));
            }
        }
        for (k, (s, mask, loc, what)) in b.fixes.iter().enumerate() {
            o.line("");
            o.line(format!("[[bodies.fix]]  {}", o.at(what, *loc)));
            select(&mut o, s);
            o.line(format!("dofs = {}", dofs(*mask)));
            o.origin(&format!("{key}.fix[{k}]"), *loc, what);
        }
        for (k, p) in b.prescribes.iter().enumerate() {
            o.line("");
            o.line(format!("[[bodies.prescribe]]  {}", o.at(&p.what, p.loc)));
            select(&mut o, &p.sel);
            let kind = if p.displacement {
                "displacement"
            } else {
                "velocity"
            };
            o.line(format!("{kind} = {}", v3(p.v)));
            if p.w != [0.0; 3] {
                o.line(format!("angular_velocity = {}", v3(p.w)));
            }
            if let Some(c) = p.curve {
                o.line(format!("curve = \"lc{c}\""));
            }
            if let Some(r) = p.ramp {
                o.line(format!(
                    "ramp = {r:?}  # the DOFs' curves, all ramps to {r:?} s"
                ));
            }
            o.origin(&format!("{key}.prescribe[{k}]"), p.loc, &p.what);
        }
        for (k, l) in b.loads.iter().enumerate() {
            o.line("");
            o.line(format!(
                "[[bodies.load]]  {} (force: SF x the number of nodes)",
                o.at(&l.what, l.loc)
            ));
            select(&mut o, &l.sel);
            if let Some(f) = l.force {
                o.line(format!("force = {}", v3(f)));
            }
            if let Some(f) = l.moment {
                o.line(format!("moment = {}", v3(f)));
            }
            o.line(format!("curve = \"lc{}\"", l.curve));
            o.origin(&format!("{key}.load[{k}]"), l.loc, &l.what);
        }
        for (k, p) in b.pressures.iter().enumerate() {
            o.line("");
            o.line(format!(
                "[[bodies.pressure]]  {} (Pa; positive against the element normal)",
                o.at(&p.what, p.loc)
            ));
            o.line(format!("value = {:?}", p.value));
            o.line(format!("curve = \"lc{}\"", p.curve));
            if let Some(ids) = &p.elements {
                o.line(format!("elements = [{}]", id_list(ids)));
            }
            o.origin(&format!("{key}.pressure[{k}]"), p.loc, &p.what);
        }
        meshes.push((file, b.surface, b.element_files));
    }
    Converted {
        toml: o.text,
        meshes,
        files: deck.lx.files.clone(),
        origins: o.origins,
        notes: m.notes,
    }
}
