//! The MEIM (Macro Entity Interaction Multigraph): nodes are bodies, edges are possible
//! contacts found by the level-i search (thickness-inflated body boxes that overlap
//! within the margin). Groups are its connected components.
//!
//! Edges appear as soon as two boxes come within the margin (groups merge at once) and
//! disappear only after the boxes have stayed apart for `split_after` consecutive
//! updates (groups split only when separation persists: no ping-pong of bodies between
//! workers when two bodies graze each other).
//!
//! Order is part of determinism: nodes are added in body-id order (StableGraph keeps
//! indices), pairs arrive sorted, and groups are sorted by their smallest body id with
//! members in id order.

use crash_core::contact::{candidate_pairs, BodyBox};
use petgraph::stable_graph::{EdgeIndex, NodeIndex, StableGraph};
use petgraph::unionfind::UnionFind;
use petgraph::Undirected;
use std::collections::HashMap;

/// A possible contact between two bodies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
    edges: HashMap<(u32, u32), EdgeIndex>,
    split_after: u64,
    groups: Vec<Vec<u32>>,
}

/// Level-i search: candidate pairs (ids, a < b, sorted) among `boxes`. The contact
/// engine's own broad phase (`crash_core::contact::candidate_pairs`): the MEIM then
/// contains every pair the contact stage can see, by construction.
pub fn box_pairs(boxes: &[BodyBox], margin: f64) -> Vec<(u32, u32)> {
    candidate_pairs(boxes, margin)
}

impl Meim {
    /// A graph of isolated bodies. `ids` need not be sorted.
    pub fn new(ids: &[u32], split_after: u64) -> Self {
        let mut sorted = ids.to_vec();
        sorted.sort_unstable();
        let mut graph = StableGraph::with_capacity(sorted.len(), sorted.len());
        let nodes = sorted.iter().map(|&id| graph.add_node(id)).collect();
        let groups = sorted.iter().map(|&id| vec![id]).collect();
        Self {
            graph,
            ids: sorted,
            nodes,
            edges: HashMap::new(),
            split_after,
            groups,
        }
    }

    fn index(&self, id: u32) -> Option<usize> {
        self.ids.binary_search(&id).ok()
    }

    /// Apply the pairs found at update `step`. Returns true when the groups changed.
    pub fn update(&mut self, step: u64, pairs: &[(u32, u32)]) -> bool {
        let mut changed = false;
        for &(a, b) in pairs {
            let key = (a.min(b), a.max(b));
            if let Some(&e) = self.edges.get(&key) {
                if let Some(w) = self.graph.edge_weight_mut(e) {
                    w.seen = step;
                }
                continue;
            }
            let (Some(ia), Some(ib)) = (self.index(key.0), self.index(key.1)) else {
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
            self.edges.insert(key, e);
            changed = true;
        }
        let stale: Vec<(u32, u32)> = self
            .edges
            .iter()
            .filter(|(_, &e)| {
                self.graph
                    .edge_weight(e)
                    .is_some_and(|w| step.saturating_sub(w.seen) > self.split_after)
            })
            .map(|(k, _)| *k)
            .collect();
        for k in stale {
            if let Some(e) = self.edges.remove(&k) {
                self.graph.remove_edge(e);
                changed = true;
            }
        }
        if changed {
            self.groups = self.components();
        }
        changed
    }

    fn components(&self) -> Vec<Vec<u32>> {
        let n = self.ids.len();
        let mut uf = UnionFind::<usize>::new(n);
        for e in self.graph.edge_indices() {
            if let Some((a, b)) = self.graph.edge_endpoints(e) {
                uf.union(a.index(), b.index());
            }
        }
        // Nodes were added in id order with no removals: node index k is ids[k].
        let mut by_root: HashMap<usize, usize> = HashMap::new();
        let mut groups: Vec<Vec<u32>> = Vec::new();
        for k in 0..n {
            let r = uf.find_mut(k);
            let g = *by_root.entry(r).or_insert_with(|| {
                groups.push(Vec::new());
                groups.len() - 1
            });
            groups[g].push(self.ids[k]);
        }
        // ids ascending, so each group is sorted and groups appear by smallest id.
        groups
    }

    /// Connected components: sorted by smallest body id, members ascending.
    pub fn groups(&self) -> &[Vec<u32>] {
        &self.groups
    }

    /// Current edges (a < b), sorted.
    pub fn pairs(&self) -> Vec<(u32, u32)> {
        let mut p: Vec<(u32, u32)> = self.edges.keys().copied().collect();
        p.sort_unstable();
        p
    }

    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The interaction between two bodies, if there is an edge.
    pub fn interaction(&self, a: u32, b: u32) -> Option<Interaction> {
        let e = self.edges.get(&(a.min(b), a.max(b)))?;
        self.graph.edge_weight(*e).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_merge_at_once_and_split_after_persistent_separation() {
        let mut m = Meim::new(&[7, 3, 5, 1], 2);
        assert_eq!(m.groups(), &[vec![1], vec![3], vec![5], vec![7]]);
        assert!(m.update(1, &[(3, 7), (1, 5)]));
        assert_eq!(m.groups(), &[vec![1, 5], vec![3, 7]]);
        assert!(m.update(2, &[(1, 5), (5, 7)]));
        assert_eq!(m.groups(), &[vec![1, 3, 5, 7]]);
        // (3, 7) last seen at 1: kept through updates 2 and 3, dropped at 4.
        assert!(!m.update(3, &[(1, 5), (5, 7)]));
        assert!(m.update(4, &[(1, 5)]));
        assert_eq!(m.groups(), &[vec![1, 5, 7], vec![3]]);
        assert!(!m.update(5, &[(1, 5)]));
        assert_eq!(m.interaction(5, 1).map(|i| i.since), Some(1));
        assert_eq!(m.pairs(), vec![(1, 5), (5, 7)]);
        // unknown ids are ignored
        assert!(!m.update(6, &[(1, 5), (5, 7), (2, 9)]));
    }
}
