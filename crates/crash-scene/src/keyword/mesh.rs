//! One mesh per *PART: its shells (triangles first, then quads, each in deck order), the
//! nodes they use (in *NODE order) with their deck ids. A node used by two parts is
//! refused: crash bodies are separate meshes.

use super::convert::{BodyOut, Index};
use super::DeckError;
use crate::msh::MshSurface;
use crash_core::{Mesh, Vec3};
use std::collections::{BTreeMap, HashMap};

pub(super) fn bodies(ix: &mut Index<'_>) -> Result<Vec<BodyOut>, DeckError> {
    let d = ix.deck;
    if d.parts.is_empty() {
        return Err(super::DeckError {
            file: d.lx.files.first().cloned().unwrap_or_default(),
            line: 0,
            column: 0,
            keyword: "PART".into(),
            message: "the deck defines no *PART: there is nothing to run".into(),
        });
    }
    let mut shells_of: BTreeMap<i64, Vec<usize>> = BTreeMap::new();
    let mut eids = HashMap::with_capacity(d.shells.len());
    for (k, s) in d.shells.iter().enumerate() {
        if let Some(old) = eids.insert(s.id, s.loc) {
            return Err(ix.err(
                s.loc,
                "ELEMENT_SHELL",
                format!("element {} is defined twice (first at {})", s.id, d.at(old)),
            ));
        }
        if !d.parts.contains_key(&s.part) {
            return Err(ix.err(
                s.loc,
                "ELEMENT_SHELL",
                format!("element {}: part {} is not defined (*PART)", s.id, s.part),
            ));
        }
        shells_of.entry(s.part).or_default().push(k);
    }
    for (b, (pid, p)) in d.parts.iter().enumerate() {
        if !shells_of.contains_key(pid) {
            return Err(ix.err(
                p.loc,
                "PART",
                format!(
                "part {pid} has no *ELEMENT_SHELL: every part becomes a body, which needs elements"
            ),
            ));
        }
        if !d.sections.contains_key(&p.secid) {
            return Err(ix.err(
                p.loc,
                "PART",
                format!(
                    "part {pid}: SECID {} is not defined (*SECTION_SHELL)",
                    p.secid
                ),
            ));
        }
        if !d.mats.contains_key(&p.mid) {
            return Err(ix.err(
                p.loc,
                "PART",
                format!(
                    "part {pid}: MID {} is not defined (*MAT_ELASTIC or *MAT_RIGID)",
                    p.mid
                ),
            ));
        }
        ix.body_of.insert(*pid, b);
    }
    // which part owns each node (and through which element, for the message)
    let mut first: Vec<Option<(usize, usize)>> = vec![None; d.nodes.len()];
    for (pid, list) in &shells_of {
        let b = ix.body_of[pid];
        for &k in list {
            let s = &d.shells[k];
            for &nid in &s.nodes {
                let n = *ix.node.get(&nid).ok_or_else(|| {
                    ix.err(
                        s.loc,
                        "ELEMENT_SHELL",
                        format!(
                            "element {} refers to node {nid}, which is not defined (*NODE)",
                            s.id
                        ),
                    )
                })?;
                match first[n] {
                    None => first[n] = Some((b, k)),
                    Some((b2, k2)) if b2 != b => {
                        let (e2, p2) = (&d.shells[k2], d.shells[k2].part);
                        return Err(ix.err(s.loc, "ELEMENT_SHELL", format!(
                            "node {nid} is shared by part {p2} (element {} at {}) and part {pid} (element {}): crash bodies are separate meshes, so parts may not share nodes; give each part its own nodes",
                            e2.id, d.at(e2.loc), s.id
                        )));
                    }
                    Some(_) => {}
                }
            }
        }
    }
    let mut out: Vec<BodyOut> = Vec::with_capacity(d.parts.len());
    let headings: Vec<&str> = d.parts.values().map(|p| p.heading.trim()).collect();
    for (pid, p) in &d.parts {
        let h = p.heading.trim();
        let unique = !h.is_empty() && headings.iter().filter(|x| **x == h).count() == 1;
        out.push(BodyOut {
            pid: *pid,
            name: if unique {
                h.to_string()
            } else {
                format!("part {pid}")
            },
            loc: p.loc,
            mid: p.mid,
            secid: p.secid,
            surface: MshSurface {
                mesh: Mesh::default(),
                element_tags: Vec::new(),
                node_tags: Vec::new(),
            },
            element_files: Vec::new(),
            fixes: Vec::new(),
            prescribes: Vec::new(),
            loads: Vec::new(),
            pressures: Vec::new(),
            velocity: None,
            contact: false,
            self_contact: false,
        });
    }
    for (n, f) in first.iter().enumerate() {
        if let Some((b, _)) = *f {
            let s = &mut out[b].surface;
            ix.owner[n] = Some((b, s.node_tags.len() as u32));
            let node = &d.nodes[n];
            s.mesh
                .nodes
                .push(Vec3::new(node.x[0], node.x[1], node.x[2]));
            s.node_tags.push(node.id as u64);
        }
    }
    for tris in [true, false] {
        for (pid, list) in &shells_of {
            let body = &mut out[ix.body_of[pid]];
            for &k in list {
                let s = &d.shells[k];
                if (s.nodes.len() == 3) != tris {
                    continue;
                }
                let local: Vec<u32> = s
                    .nodes
                    .iter()
                    .map(|id| ix.owner[ix.node[id]].map_or(0, |o| o.1))
                    .collect();
                let m = &mut body.surface.mesh;
                if tris {
                    m.tris.push([local[0], local[1], local[2]]);
                } else {
                    m.quads.push([local[0], local[1], local[2], local[3]]);
                }
                body.surface.element_tags.push((s.id as u64, s.loc.line));
                body.element_files.push(s.loc.file);
            }
        }
    }
    Ok(out)
}
