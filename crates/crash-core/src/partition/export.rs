//! What a part of a group shared between workers sends the other holders each step
//! (`PartState`), and which of its nodes (`exports`: the owned nodes another part
//! reads). Every holder derives the same lists from the split and the views.

use super::GroupSplit;
use crate::Vec3;

/// The owned nodes of one part after its integration that the other holders of its
/// group import, and its figures.
#[derive(Debug, Clone, PartialEq)]
pub struct PartState {
    /// Body id and part index.
    pub id: u32,
    pub part: u32,
    /// Each of x, v, w: at every owned node (in order), or at the part's export nodes
    /// only (`SharedGroup::export`, known to every holder from the last view build).
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    pub w: Vec<Vec3>,
    /// Box of the owned nodes (the body's box is the min/max over its parts).
    pub lo: Vec3,
    pub hi: Vec3,
    /// Largest distance of an owned node from where the contact views were built.
    pub far: f64,
    /// Largest move of an owned node in the step and that node (whole-body index).
    pub max_move: f64,
    pub max_move_node: u32,
    /// Momentum of the owned nodes on the body's fixed quantum (the closing speed's
    /// mean velocity: `contact::sweep::Momentum`).
    pub momentum: crate::contact::sweep::Momentum,
}

/// Per body and part: the owned nodes (local indices) that a part on another holder
/// reads, as a halo node or a node of that holder's contact view (the views of every
/// holder, built or not). A part on the same holder reads them in place (a floor's
/// part under the spheres that holder computes).
pub(super) fn exports(split: &GroupSplit) -> Vec<Vec<Vec<u32>>> {
    let holder = split.holder_keys();
    let apart = |i: usize, q: usize, j: usize, r: usize| holder[i][q] != holder[j][r];
    let mut needed: Vec<Vec<bool>> = split
        .whole
        .iter()
        .map(|b| vec![false; b.def.node_count()])
        .collect();
    for (i, s) in split.splits.iter().enumerate() {
        for (q, p) in s.parts.iter().enumerate() {
            for &n in &p.node[p.owned..] {
                if apart(i, q, i, s.owner[n as usize].0 as usize) {
                    needed[i][n as usize] = true;
                }
            }
        }
    }
    // what a holder's view reads of the parts on other holders
    for view in &split.views {
        for (&j, nodes) in view.index.iter().zip(&view.node) {
            for &n in nodes {
                let r = split.splits[j].owner[n as usize].0 as usize;
                if !view.gives(j, r) {
                    needed[j][n as usize] = true;
                }
            }
        }
    }
    split
        .splits
        .iter()
        .zip(&needed)
        .map(|(s, need)| {
            s.parts
                .iter()
                .map(|p| {
                    (0..p.owned as u32)
                        .filter(|&k| need[p.node[k as usize] as usize])
                        .collect()
                })
                .collect()
        })
        .collect()
}
