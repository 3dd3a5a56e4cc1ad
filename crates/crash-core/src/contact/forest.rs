//! A body's segment boxes as a few R-trees over disjoint spatial groups, built on the
//! pool: one bulk load of a whole large body was the largest serial part of the contact
//! stage (a sphere falling through its skin rebuilds every few hundred passes, each
//! time with one thread busy and the other idle).
//!
//! A query asks every tree and concatenates the answers, so it returns exactly the set
//! one tree over all boxes would return (rstar's inclusive box test on the same stored
//! corners), in another order: every user either sorts the candidates
//! (`sweep::first_crossing`, `quadrature`) or picks among them by exact distance and
//! lowest index (`narrow::search`, the Verlet lists of `verlet.rs`), so no result
//! depends on the grouping.

use rayon::prelude::*;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, RTreeObject, AABB};

/// A segment's stored box and its index.
pub type Entry = GeomWithData<Rectangle<[f64; 3]>, u32>;

/// Largest group of boxes per tree: a body above it is halved (at the median of the box
/// centres along its longest side) until every group fits. Big enough that a query
/// meets few trees, small enough that a large body's build fills both threads.
pub const GROUP: usize = 4096;

/// The trees of one body's segment boxes.
#[derive(Debug, Clone, Default)]
pub struct Forest {
    trees: Vec<RTree<Entry>>,
}

impl Forest {
    /// Bulk-load the boxes: split into spatial groups of at most `GROUP`, one tree per
    /// group, the groups loaded on the pool.
    pub fn build(entries: Vec<Entry>) -> Self {
        Self {
            trees: split(entries)
                .into_par_iter()
                .map(RTree::bulk_load)
                .collect(),
        }
    }

    /// Indices of the boxes that meet the box `lo`..`hi` (lo <= hi), into `out`.
    pub fn query(&self, lo: [f64; 3], hi: [f64; 3], out: &mut Vec<u32>) {
        out.clear();
        let q = AABB::from_corners(lo, hi);
        for t in &self.trees {
            out.extend(t.locate_in_envelope_intersecting(&q).map(|e| e.data));
        }
    }

    /// Number of trees.
    pub fn len(&self) -> usize {
        self.trees.len()
    }

    pub fn is_empty(&self) -> bool {
        self.trees.is_empty()
    }
}

/// Centre of an entry's box along axis `d` (times two: only the order matters).
fn centre(e: &Entry, d: usize) -> f64 {
    let env = e.geom().envelope();
    env.lower()[d] + env.upper()[d]
}

/// Halve `entries` at the median centre along the longest side of their centres' box
/// until each part holds at most `GROUP` (the halves on the pool), the parts in order.
fn split(mut entries: Vec<Entry>) -> Vec<Vec<Entry>> {
    if entries.len() <= GROUP {
        return vec![entries];
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for e in &entries {
        for d in 0..3 {
            let c = centre(e, d);
            lo[d] = lo[d].min(c);
            hi[d] = hi[d].max(c);
        }
    }
    // NaN extents (a broken state) compare as 0 here: any axis gives a valid split
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    let mid = entries.len() / 2;
    entries.select_nth_unstable_by(mid, |a, b| centre(a, axis).total_cmp(&centre(b, axis)));
    let upper = entries.split_off(mid);
    let (mut parts, rest) = rayon::join(|| split(entries), || split(upper));
    parts.extend(rest);
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A query over the grouped trees answers the same set as one tree over all the
    /// boxes (random boxes, queries of all sizes, some empty or out of range).
    #[test]
    fn forest_queries_answer_the_set_of_one_tree() {
        let mut r = 987654321u64;
        let mut rnd = || {
            r = r
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (r >> 11) as f64 / (1u64 << 53) as f64
        };
        let entries: Vec<Entry> = (0..3 * GROUP + 517)
            .map(|j| {
                let p = [rnd(), 0.3 * rnd(), 0.1 * rnd()];
                let s = 0.01 * rnd();
                let q = [p[0] + s, p[1] + s, p[2] + s];
                GeomWithData::new(Rectangle::from_corners(p, q), j as u32)
            })
            .collect();
        let one = RTree::bulk_load(entries.clone());
        let forest = Forest::build(entries);
        assert!(forest.len() >= 4, "{}", forest.len());
        let (mut a, mut nonempty) = (Vec::new(), 0);
        for k in 0..500 {
            let p = [1.2 * rnd() - 0.1, 0.4 * rnd() - 0.05, 0.2 * rnd() - 0.05];
            let s = if k % 2 == 0 {
                0.02 * rnd()
            } else {
                0.2 * rnd()
            };
            let (lo, hi) = (p, [p[0] + s, p[1] + s, p[2] + s]);
            forest.query(lo, hi, &mut a);
            let mut want: Vec<u32> = one
                .locate_in_envelope_intersecting(&AABB::from_corners(lo, hi))
                .map(|e| e.data)
                .collect();
            a.sort_unstable();
            want.sort_unstable();
            assert_eq!(a, want, "query {k}");
            nonempty += usize::from(!want.is_empty());
        }
        assert!(nonempty > 100 && nonempty < 500, "{nonempty}");
    }
}
