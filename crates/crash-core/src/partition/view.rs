//! Contact views of a split group (`GroupSplit`): what each holder's view holds,
//! how it is selected and filled (the reach rule is in `contact`'s module text).

use super::select::{select, Boxes, Reach};
use super::select_points::{select_segments, union, SegmentReach};
use super::{GroupSplit, Split};
use crate::body::Body;
use crate::contact::{ContactPass, ContactState};
use crate::error::{CoreError, Fault};
use std::collections::BTreeMap;

/// What a contact view holds, for the tests that show each piece is needed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ViewRule {
    /// One ring of segments around the view's nodes (complete nodal normals).
    pub ring: bool,
    /// Node masses copied from the whole bodies (else the view's own lumped masses,
    /// partial where a node's elements are not all in the view).
    pub whole_masses: bool,
}

impl Default for ViewRule {
    fn default() -> Self {
        Self {
            ring: true,
            whole_masses: true,
        }
    }
}

/// The contact view of one holder: of its parts, or of one part where every part is
/// its own holder (no holder table).
#[derive(Debug, Clone)]
pub struct View {
    /// One sub-body per contact body with nodes here, in the group's order.
    pub bodies: Vec<Body>,
    /// The group body of each view body.
    pub index: Vec<usize>,
    /// View node -> node of the whole body, per view body.
    pub node: Vec<Vec<u32>>,
    /// View element -> element of the whole body, per view body.
    pub element: Vec<Vec<u32>>,
    /// Where each view body's nodes come from (the fill), per view body: runs of view
    /// nodes owned by one part at consecutive indices there.
    pub(super) fill: Vec<Vec<Run>>,
    /// The parts whose contact forces this view gives, as (body, part), in order.
    pub parts: Vec<(usize, usize)>,
    /// Per part of `parts` of a contact body: its body among `bodies` and the view
    /// index of each owned node.
    pub(super) owned_at: Vec<Option<OwnedAt>>,
    /// Per view body and view node: owned by one of `parts` (the contact statistics
    /// book the pushes of these slave nodes only: each push once over all views).
    pub(super) counted: Vec<Vec<bool>>,
    /// Per view body and view element: counted by one of `parts` (the segment pass's
    /// statistics book the points of these slave segments only).
    pub(super) counted_segments: Vec<Vec<bool>>,
    /// Per view body and view element under the segment pass: its points can push an
    /// owned node (the segments searched as slaves; empty: all).
    pub(super) slave_segments: Vec<Vec<bool>>,
    pub(super) state: ContactState,
}

impl View {
    fn empty(parts: Vec<(usize, usize)>) -> Self {
        Self {
            bodies: Vec::new(),
            index: Vec::new(),
            node: Vec::new(),
            element: Vec::new(),
            fill: Vec::new(),
            parts,
            owned_at: Vec::new(),
            counted: Vec::new(),
            counted_segments: Vec::new(),
            slave_segments: Vec::new(),
            state: ContactState::default(),
        }
    }

    /// Does this view give the forces of part q of body i (a part on its holder)?
    pub fn gives(&self, i: usize, q: usize) -> bool {
        self.parts.binary_search(&(i, q)).is_ok()
    }
}

impl GroupSplit {
    /// The parts of each contact view, in order: the parts of each holder (by holder
    /// number), or each part alone without a holder table (or one that does not fit).
    pub fn view_parts(&self) -> Vec<Vec<(usize, usize)>> {
        let holder = self.holder_keys();
        let mut by: BTreeMap<(u32, usize, usize), Vec<(usize, usize)>> = BTreeMap::new();
        for (i, keys) in holder.iter().enumerate() {
            for (q, &k) in keys.iter().enumerate() {
                by.entry(k).or_default().push((i, q));
            }
        }
        by.into_values().collect()
    }

    /// Who holds each part (`[i][q]`), as a key equal for parts on one holder: the
    /// holder table's number, or each part its own key without a table (or with one
    /// that does not fit the split). The views and the export lists both read it.
    pub(super) fn holder_keys(&self) -> Vec<Vec<(u32, usize, usize)>> {
        let fits = self.holder.len() == self.splits.len()
            && self
                .holder
                .iter()
                .zip(&self.splits)
                .all(|(h, s)| h.len() == s.parts.len());
        self.splits
            .iter()
            .enumerate()
            .map(|(i, s)| {
                (0..s.parts.len())
                    .map(|q| {
                        if fits {
                            (self.holder[i][q], 0, 0)
                        } else {
                            (u32::MAX, i, q)
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// Build the contact view of every holder at the current (gathered) positions.
    /// A holder's view is the union of its parts' views (the nodes and segments within
    /// reach of one of their elements, and the ring): every hit on one of its owned
    /// nodes is computed once, on that view, with the whole group's bits.
    pub(super) fn build_views(&mut self) -> Result<(), CoreError> {
        let tmax = self
            .whole
            .iter()
            .filter(|b| b.def.contact)
            .map(|b| b.def.section.thickness)
            .fold(0.0, f64::max);
        let g = tmax + 2.0 * self.skin;
        // every element of every contact body
        let every: Vec<Option<Vec<u32>>> = self
            .whole
            .iter()
            .map(|b| {
                b.def
                    .contact
                    .then(|| (0..b.def.element_count() as u32).collect())
            })
            .collect();
        let all = Boxes::of_elements(&self.whole, &every);
        let g_segments = SegmentReach::of(&self.whole, self.skin);
        let mut views = Vec::new();
        for parts in self.view_parts() {
            let mine = parts.iter().any(|&(i, q)| self.mine[i][q]);
            let mut view = View::empty(parts);
            if !mine && !self.all_lists {
                // another worker's parts: their view is built there
                views.push(view);
                continue;
            }
            // only the parts of contact bodies read contact forces
            // the holder's parts' elements, per body (only the parts of contact
            // bodies read contact forces)
            let mut lists: Vec<Option<Vec<u32>>> = vec![None; self.whole.len()];
            for &(i, q) in view
                .parts
                .iter()
                .filter(|&&(i, _)| self.whole[i].def.contact)
            {
                let l = lists[i].get_or_insert_with(Vec::new);
                l.extend_from_slice(&self.splits[i].parts[q].element);
            }
            let boxes = Boxes::of_elements(&self.whole, &lists);
            let reach = Reach {
                all: &all,
                mine: &boxes,
                g,
                ring: self.rule.ring,
            };
            let owned = |j: usize, n: u32| {
                let q = self.splits[j].owner[n as usize].0 as usize;
                view.gives(j, q)
            };
            let mut slaves = Vec::new();
            let picked = if self.contact.pass == ContactPass::Segments {
                // the segment pass's reach (select_points.rs); the node passes' rule
                // stays for self-contact, which runs node to segment
                let (segs, s) = select_segments(&self.whole, &lists, &all, &g_segments);
                slaves = s;
                if self.whole.iter().any(|b| b.def.self_contact) {
                    union(select(&self.whole, owned, &reach), segs)
                } else {
                    segs
                }
            } else {
                select(&self.whole, owned, &reach)
            };
            for (j, (b, (node, element))) in self.whole.iter().zip(picked).enumerate() {
                if node.is_empty() {
                    continue;
                }
                if !mine {
                    // its node lists only (what it imports)
                    view.index.push(j);
                    view.node.push(node);
                    view.element.push(element);
                    continue;
                }
                let mut vb = super::parts::sub_body(b, &node, &element, node.len())?;
                // the segment pass reads the whole body's figures (stiffness, slave side)
                vb.def_mut().whole_surface = self.surfaces[j].as_ref().map(|s| s.figures);
                if !self.rule.whole_masses {
                    let m = crate::mesh::Mesh {
                        nodes: vb.def.x0.clone(),
                        tris: vb.def.tris.iter().map(|e| e.nodes).collect(),
                        quads: vb.def.quads.iter().map(|e| e.nodes).collect(),
                    };
                    let own = Body::new(b.def.id, &b.def.name, &m, b.def.section, b.def.stab)?;
                    vb.def_mut().mass = own.def.mass.clone();
                }
                view.bodies.push(vb);
                if let Some(s) = slaves.get(j) {
                    let flags = element.iter().map(|e| s.binary_search(e).is_ok()).collect();
                    view.slave_segments.push(flags);
                }
                view.fill
                    .push(runs(node.iter().map(|&n| self.splits[j].owner[n as usize])));
                view.index.push(j);
                view.node.push(node);
                view.element.push(element);
            }
            if mine {
                view.owned_at = owned_at(&view, &self.splits, &self.whole);
                view.counted = counted(&view);
                view.counted_segments = counted_segments(&view, &self.splits);
            }
            views.push(view);
        }
        self.views = views;
        self.reference = self.whole.iter().map(|b| b.state.x.clone()).collect();
        self.builds += 1;
        Ok(())
    }
}

/// View nodes `view..view + len` owned by part `part`, at `local..local + len` there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Run {
    pub(super) part: u32,
    pub(super) view: u32,
    pub(super) local: u32,
    pub(super) len: u32,
}

/// The runs of a view body whose node k is owned by `owner[k]` = (part, local index).
fn runs(owner: impl Iterator<Item = (u32, u32)>) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    for (k, (part, local)) in owner.enumerate() {
        let k = k as u32;
        match out.last_mut() {
            Some(r) if r.part == part && r.view + r.len == k && r.local + r.len == local => {
                r.len += 1
            }
            _ => out.push(Run {
                part,
                view: k,
                local,
                len: 1,
            }),
        }
    }
    out
}

/// A part's body among its view's bodies, and the view index of each owned node
/// (`NOT_IN_VIEW` for an owned node no hit can touch: its contact force is zero).
pub(super) type OwnedAt = (usize, Vec<u32>);

/// The view index of an owned node that is not in the view.
pub(super) const NOT_IN_VIEW: u32 = u32::MAX;

/// Per part of a view (of a contact body with nodes in the view): its body among the
/// view's bodies and the view index of each of its owned nodes.
fn owned_at(view: &View, splits: &[Split], whole: &[Body]) -> Vec<Option<OwnedAt>> {
    view.parts
        .iter()
        .map(|&(i, q)| {
            if !whole[i].def.contact {
                return None;
            }
            let k = view.index.iter().position(|&j| j == i)?;
            let p = &splits[i].parts[q];
            let at = p.node[..p.owned]
                .iter()
                .map(|n| {
                    view.node[k]
                        .binary_search(n)
                        .map_or(NOT_IN_VIEW, |k| k as u32)
                })
                .collect();
            Some((k, at))
        })
        .collect()
}

/// Per view body, which view nodes the view's parts own (from `owned_at`).
fn counted(view: &View) -> Vec<Vec<bool>> {
    let mut out: Vec<Vec<bool>> = view
        .bodies
        .iter()
        .map(|b| vec![false; b.state.x.len()])
        .collect();
    for (own, at) in view.owned_at.iter().flatten() {
        for &k in at.iter().filter(|&&k| k != NOT_IN_VIEW) {
            out[*own][k as usize] = true;
        }
    }
    out
}

/// Per view body, which view elements one of the view's parts counts (its owner: the
/// part owning the element's first node, `BodyDef::uncounted`).
fn counted_segments(view: &View, splits: &[Split]) -> Vec<Vec<bool>> {
    view.index
        .iter()
        .zip(&view.element)
        .take(view.bodies.len())
        .map(|(&j, element)| {
            let mut out = vec![false; element.len()];
            for &(i, q) in view.parts.iter().filter(|&&(i, _)| i == j) {
                let p = &splits[i].parts[q];
                let uncounted = p.body.def.uncounted.as_deref();
                for (k, &e) in p.element.iter().enumerate() {
                    if uncounted.is_some_and(|u| u[k]) {
                        continue;
                    }
                    if let Ok(at) = element.binary_search(&e) {
                        out[at] = true;
                    }
                }
            }
            out
        })
        .collect()
}

/// A fault found on a view, with the whole body's node and segment numbers.
pub(super) fn in_whole(mut f: Fault, view: &View) -> Fault {
    if let Fault::PassThrough {
        body,
        node,
        other,
        segment,
        ..
    } = &mut f
    {
        let at = |id: u32| view.bodies.iter().position(|b| b.def.id == id);
        if let Some(k) = at(*body) {
            *node = view.node[k][*node] as usize;
        }
        if let Some(k) = at(*other) {
            *segment = view.element[k][*segment] as usize;
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The runs cover every view node once, each from its owner at its local index.
    #[test]
    fn runs_map_every_view_node_to_its_owner() {
        let owner = [
            (0, 5),
            (0, 6),
            (0, 7),
            (1, 0),
            (1, 1),
            (0, 9),
            (0, 10),
            (1, 3),
        ];
        let r = runs(owner.iter().copied());
        assert_eq!(r.len(), 4, "{r:?}");
        let mut back = Vec::new();
        for run in &r {
            assert_eq!(run.view as usize, back.len(), "runs in view order, no gap");
            back.extend((0..run.len).map(|k| (run.part, run.local + k)));
        }
        assert_eq!(back, owner);
        assert!(runs(std::iter::empty()).is_empty());
    }
}
