//! The MEIM (Macro Entity Interaction Multigraph): nodes are bodies, edges are possible
//! contacts found by the level-i search (thickness-inflated body boxes that overlap
//! within the margin). Groups are its connected components.
//!
//! Edges appear as soon as two boxes come within the margin (groups merge at once) and
//! disappear only after the boxes have stayed apart for `split_after` consecutive
//! updates (groups split only when separation persists: no ping-pong of bodies between
//! workers when two bodies graze each other).
//!
//! Kinematic bodies (every degree of freedom prescribed) keep their edges (the contact
//! pairs) but never link two bodies into one group: nothing flows back into their
//! motion. Each is a group of its own, and every group with an edge to one holds a
//! read-only copy of it (`copies`).
//!
//! Order is part of determinism: nodes are added in body-id order (StableGraph keeps
//! indices), pairs arrive sorted, and groups are sorted by their smallest body id with
//! members in id order.

use crash_core::contact::{candidate_pairs, BodyBox};
use petgraph::stable_graph::{EdgeIndex, NodeIndex, StableGraph};
use petgraph::unionfind::UnionFind;
use petgraph::Undirected;

/// A possible contact between two bodies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Interaction {
    /// Update (step) at which the boxes first came within the margin.
    pub since: u64,
    /// Last update at which they were within the margin.
    pub seen: u64,
}

#[derive(Debug, Clone)]
pub struct Meim {
    graph: StableGraph<u32, Interaction, Undirected>,
    /// Body ids in ascending order; node `k` of the graph is body `ids[k]`.
    ids: Vec<u32>,
    nodes: Vec<NodeIndex>,
    /// Current edges: (a, b) with a < b by id, sorted, and their graph edge.
    edges: Vec<((u32, u32), EdgeIndex)>,
    split_after: u64,
    /// Groups in CSR form: members of group k are `members[start[k]..start[k + 1]]`.
    start: Vec<u32>,
    members: Vec<u32>,
    /// Group of each body (by position in `ids`).
    group_of: Vec<u32>,
    /// Kinematic flag of each body (by position in `ids`).
    kinematic: Vec<bool>,
    /// Read-only copies of each group (kinematic ids with an edge to a member), CSR.
    copy_start: Vec<u32>,
    copy_ids: Vec<u32>,
}

/// Level-i search: candidate pairs (ids, a < b, sorted) among `boxes`. The contact
/// engine's own broad phase (`crash_core::contact::candidate_pairs`): the MEIM then
/// contains every pair the contact stage can see, by construction. (The master calls
/// it through `pairs::PairSearch`, which caches it between steps.)
pub fn box_pairs(boxes: &[BodyBox], margin: f64) -> Vec<(u32, u32)> {
    candidate_pairs(boxes, margin)
}

impl Meim {
    /// A graph of isolated bodies. `ids` need not be sorted.
    pub fn new(ids: &[u32], split_after: u64) -> Self {
        let mut sorted = ids.to_vec();
        sorted.sort_unstable();
        let n = sorted.len();
        let mut graph = StableGraph::with_capacity(n, n);
        let nodes = sorted.iter().map(|&id| graph.add_node(id)).collect();
        Self {
            graph,
            members: sorted.clone(),
            ids: sorted,
            nodes,
            edges: Vec::new(),
            split_after,
            start: (0..=n as u32).collect(),
            group_of: (0..n as u32).collect(),
            kinematic: vec![false; n],
            copy_start: vec![0; n + 1],
            copy_ids: Vec::new(),
        }
    }

    /// Mark the kinematic bodies (their edges no longer join groups).
    pub fn with_kinematic(mut self, kinematic: &[u32]) -> Self {
        for &id in kinematic {
            if let Some(i) = self.index(id) {
                self.kinematic[i] = true;
            }
        }
        self.components();
        self
    }

    /// The graph rebuilt from `edges` (as `edge_states` gives them): the same groups
    /// and split timers (for a restart). Edges naming unknown ids are ignored.
    pub fn restore(ids: &[u32], split_after: u64, edges: &[((u32, u32), Interaction)]) -> Self {
        let mut m = Self::new(ids, split_after);
        let mut sorted = edges.to_vec();
        sorted.sort_by_key(|(k, _)| *k);
        sorted.dedup_by_key(|(k, _)| *k);
        for ((a, b), w) in sorted {
            let (Some(ia), Some(ib)) = (m.index(a), m.index(b)) else {
                continue;
            };
            if a >= b {
                continue;
            }
            let e = m.graph.add_edge(m.nodes[ia], m.nodes[ib], w);
            m.edges.push(((a, b), e));
        }
        m.components();
        m
    }

    /// Every edge (a < b, sorted) with its timers.
    pub fn edge_states(&self) -> Vec<((u32, u32), Interaction)> {
        self.edges
            .iter()
            .filter_map(|&(k, e)| self.graph.edge_weight(e).map(|w| (k, *w)))
            .collect()
    }

    fn index(&self, id: u32) -> Option<usize> {
        // ids are usually 0..n: the direct slot first, the search otherwise
        let i = id as usize;
        if self.ids.get(i) == Some(&id) {
            return Some(i);
        }
        self.ids.binary_search(&id).ok()
    }

    /// Apply the pairs (a < b, sorted, as `box_pairs` gives them; others are sorted
    /// first) found at update
    /// `step`. Returns true when the groups changed. A linear merge of two sorted
    /// lists: no hashing, cost O(pairs + edges).
    pub fn update(&mut self, step: u64, pairs: &[(u32, u32)]) -> bool {
        let sorted;
        let pairs = if pairs.windows(2).all(|w| w[0] < w[1]) {
            pairs
        } else {
            let mut p: Vec<(u32, u32)> = pairs.iter().map(|&(a, b)| (a.min(b), a.max(b))).collect();
            p.sort_unstable();
            sorted = p;
            &sorted
        };
        let mut changed = false;
        let old = std::mem::take(&mut self.edges);
        let mut kept: Vec<((u32, u32), EdgeIndex)> = Vec::with_capacity(old.len().max(pairs.len()));
        let (mut i, mut j) = (0, 0);
        loop {
            let p = pairs.get(i).copied();
            let o = old.get(j).copied();
            match (p, o) {
                (None, None) => break,
                (Some(pk), Some((ok, e))) if pk == ok => {
                    if let Some(w) = self.graph.edge_weight_mut(e) {
                        w.seen = step;
                    }
                    kept.push((ok, e));
                    i += 1;
                    j += 1;
                }
                (Some(pk), o) if o.is_none_or(|(ok, _)| pk < ok) => {
                    i += 1;
                    if pk.0 >= pk.1 || kept.last().is_some_and(|(k, _)| *k == pk) {
                        continue; // not a < b, or a repeated pair
                    }
                    let (Some(ia), Some(ib)) = (self.index(pk.0), self.index(pk.1)) else {
                        continue;
                    };
                    let e = self.graph.add_edge(
                        self.nodes[ia],
                        self.nodes[ib],
                        Interaction {
                            since: step,
                            seen: step,
                        },
                    );
                    kept.push((pk, e));
                    changed = true;
                }
                (_, Some((ok, e))) => {
                    j += 1;
                    let stale = self
                        .graph
                        .edge_weight(e)
                        .is_none_or(|w| step.saturating_sub(w.seen) > self.split_after);
                    if stale {
                        self.graph.remove_edge(e);
                        changed = true;
                    } else {
                        kept.push((ok, e));
                    }
                }
                (Some(_), None) => i += 1, // taken by the arm above
            }
        }
        self.edges = kept;
        if changed {
            self.components();
        }
        changed
    }

    /// Connected components by union-find over the graph's edges, numbered in order
    /// of their smallest body id.
    fn components(&mut self) {
        let n = self.ids.len();
        let mut uf = UnionFind::<usize>::new(n);
        let mut touch: Vec<(usize, u32)> = Vec::new();
        for e in self.graph.edge_indices() {
            if let Some((a, b)) = self.graph.edge_endpoints(e) {
                let (a, b) = (a.index(), b.index());
                match (self.kinematic[a], self.kinematic[b]) {
                    (false, false) => {
                        uf.union(a, b);
                    }
                    (true, false) => touch.push((b, self.ids[a])),
                    (false, true) => touch.push((a, self.ids[b])),
                    (true, true) => {} // two prescribed motions: nothing to share
                }
            }
        }
        // Nodes were added in id order with no removals: node index k is ids[k].
        const NONE: u32 = u32::MAX;
        let mut label = vec![NONE; n];
        let mut sizes: Vec<u32> = Vec::new();
        for k in 0..n {
            let r = uf.find_mut(k);
            if label[r] == NONE {
                label[r] = sizes.len() as u32;
                sizes.push(0);
            }
            let g = label[r];
            self.group_of[k] = g;
            sizes[g as usize] += 1;
        }
        self.start.clear();
        self.start.push(0);
        let mut acc = 0;
        for s in &sizes {
            acc += s;
            self.start.push(acc);
        }
        let mut fill: Vec<u32> = self.start[..sizes.len()].to_vec();
        for k in 0..n {
            let g = self.group_of[k] as usize;
            self.members[fill[g] as usize] = self.ids[k];
            fill[g] += 1;
        }
        // copies: (group, kinematic id), sorted and unique
        let mut copies: Vec<(u32, u32)> = touch
            .into_iter()
            .map(|(k, id)| (self.group_of[k], id))
            .collect();
        copies.sort_unstable();
        copies.dedup();
        self.copy_start.clear();
        self.copy_start.push(0);
        self.copy_ids.clear();
        let mut it = copies.iter().peekable();
        for g in 0..sizes.len() as u32 {
            while let Some(&&(_, id)) = it.peek().filter(|(cg, _)| *cg == g) {
                self.copy_ids.push(id);
                it.next();
            }
            self.copy_start.push(self.copy_ids.len() as u32);
        }
    }

    /// Read-only copies group `k` holds: the kinematic bodies with an edge to one of its
    /// members (ascending ids).
    pub fn copies(&self, k: usize) -> &[u32] {
        &self.copy_ids[self.copy_start[k] as usize..self.copy_start[k + 1] as usize]
    }

    pub fn group_count(&self) -> usize {
        self.start.len() - 1
    }

    /// Members of group `k` (ascending ids); groups are ordered by smallest id.
    pub fn group(&self, k: usize) -> &[u32] {
        &self.members[self.start[k] as usize..self.start[k + 1] as usize]
    }

    /// Connected components: sorted by smallest body id, members ascending.
    pub fn groups(&self) -> Vec<&[u32]> {
        (0..self.group_count()).map(|k| self.group(k)).collect()
    }

    /// The group of a body.
    pub fn group_of(&self, id: u32) -> Option<usize> {
        self.index(id).map(|i| self.group_of[i] as usize)
    }

    /// Current edges (a < b), sorted.
    pub fn pairs(&self) -> Vec<(u32, u32)> {
        self.edges.iter().map(|(k, _)| *k).collect()
    }

    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The interaction between two bodies, if there is an edge.
    pub fn interaction(&self, a: u32, b: u32) -> Option<Interaction> {
        let key = (a.min(b), a.max(b));
        let k = self.edges.binary_search_by_key(&key, |(k, _)| *k).ok()?;
        self.graph.edge_weight(self.edges[k].1).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_merge_at_once_and_split_after_persistent_separation() {
        let mut m = Meim::new(&[7, 3, 5, 1], 2);
        assert_eq!(m.groups(), [&[1][..], &[3], &[5], &[7]]);
        assert!(m.update(1, &[(3, 7), (1, 5)]));
        assert_eq!(m.groups(), [&[1, 5][..], &[3, 7]]);
        assert!(m.update(2, &[(1, 5), (5, 7)]));
        assert_eq!(m.groups(), [&[1, 3, 5, 7][..]]);
        // (3, 7) last seen at 1: kept through updates 2 and 3, dropped at 4.
        assert!(!m.update(3, &[(1, 5), (5, 7)]));
        assert!(m.update(4, &[(1, 5)]));
        assert_eq!(m.groups(), [&[1, 5, 7][..], &[3]]);
        assert_eq!(m.group_of(7), Some(0));
        assert_eq!(m.group_of(3), Some(1));
        assert!(!m.update(5, &[(1, 5)]));
        assert_eq!(m.interaction(5, 1).map(|i| i.since), Some(1));
        assert_eq!(m.pairs(), vec![(1, 5), (5, 7)]);
        // unknown ids are ignored
        assert!(!m.update(6, &[(1, 5), (2, 9), (5, 7)]));
    }

    #[test]
    fn a_kinematic_body_never_links_two_deformable_bodies_into_one_group() {
        // 0 is kinematic; 1 and 2 both touch it, 3 touches 2
        let mut m = Meim::new(&[0, 1, 2, 3], 2).with_kinematic(&[0]);
        assert!(m.update(1, &[(0, 1), (0, 2), (2, 3)]));
        assert_eq!(m.groups(), [&[0][..], &[1], &[2, 3]]);
        // the kinematic body is its own group and has no copies; the others copy it
        assert_eq!(m.copies(0), &[] as &[u32]);
        assert_eq!(m.copies(1), &[0]);
        assert_eq!(m.copies(2), &[0]);
        // the edges are kept (contact pairs are still searched)
        assert_eq!(m.pairs(), vec![(0, 1), (0, 2), (2, 3)]);
        // two kinematic bodies touching: no group, no copy
        let mut k = Meim::new(&[4, 5, 6], 2).with_kinematic(&[4, 5]);
        k.update(1, &[(4, 5), (5, 6)]);
        assert_eq!(k.groups(), [&[4][..], &[5], &[6]]);
        assert_eq!(k.copies(2), &[5]);
        assert_eq!(k.copies(0), &[] as &[u32]);
    }

    #[test]
    fn restored_graph_continues_like_the_original() {
        let mut m = Meim::new(&[1, 3, 5, 7], 2);
        m.update(1, &[(3, 7), (1, 5)]);
        m.update(2, &[(1, 5)]);
        let mut r = Meim::restore(&[7, 5, 3, 1], 2, &m.edge_states());
        assert_eq!(r.groups(), m.groups());
        assert_eq!(r.edge_states(), m.edge_states());
        // (3, 7) last seen at 1 splits at update 4 in both
        for step in 3..6 {
            assert_eq!(m.update(step, &[(1, 5)]), r.update(step, &[(1, 5)]));
            assert_eq!(r.groups(), m.groups());
        }
        assert_eq!(r.groups(), [&[1, 5][..], &[3], &[7]]);
    }
}
