//! Level i of the search: bodies. Each body's box is inflated by half its thickness and
//! half the search margin; overlapping boxes are candidate pairs, found by testing every
//! two boxes up to `DIRECT_MAX` bodies and with an R-tree beyond.
//! The same list feeds the master's interaction graph (MEIM) and the narrow phase.

use crate::body::Body;
use crate::Vec3;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};
use serde::{Deserialize, Serialize};

/// Axis-aligned box of a body's node positions (mid-surface) and its thickness.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BodyBox {
    pub id: u32,
    pub lo: Vec3,
    pub hi: Vec3,
    pub thickness: f64,
}

impl BodyBox {
    /// Box of a body's current positions.
    pub fn of(body: &Body) -> Self {
        Self::with_bounds(body, crate::mesh::bounds(&body.state.x))
    }

    /// Box of a body whose node bounds are known.
    pub fn with_bounds(body: &Body, (lo, hi): (Vec3, Vec3)) -> Self {
        Self {
            id: body.def.id,
            lo,
            hi,
            thickness: body.def.section.thickness,
        }
    }

    /// Half the thickness plus half the margin (margin <= 0: the thickness).
    pub fn pad(&self, margin: f64) -> f64 {
        let m = if margin > 0.0 { margin } else { self.thickness };
        0.5 * (self.thickness + m)
    }

    /// The inflated box as (lo, hi) corners.
    pub fn inflated(&self, margin: f64) -> ([f64; 3], [f64; 3]) {
        let p = self.pad(margin);
        (
            [self.lo.x - p, self.lo.y - p, self.lo.z - p],
            [self.hi.x + p, self.hi.y + p, self.hi.z + p],
        )
    }
}

/// Bodies up to which the pairs are found by testing every two boxes: up to here the
/// R-tree's bulk load costs more than the tests it saves (`cargo run --release -p
/// crash-core --example broad_pairs`, 2026-12-07: 65 bodies 2.5 against 18.9 us, 512
/// bodies 86 against 197 us, even at about 1 000; the floor's 65 bodies are searched
/// in every contact stage and once more per step on every holder of a split group).
pub const DIRECT_MAX: usize = 512;

/// Candidate body pairs (a < b by id), sorted and free of duplicates: the pairs whose
/// inflated boxes overlap. Two bodies whose surfaces are farther apart than the margin
/// are never paired. Boxes with non-finite corners are skipped (the integrator reports
/// non-finite states as faults before contact runs). Up to `DIRECT_MAX` boxes every two
/// are tested, beyond it an R-tree is searched: the same pairs either way.
pub fn candidate_pairs(boxes: &[BodyBox], margin: f64) -> Vec<(u32, u32)> {
    if boxes.len() <= DIRECT_MAX {
        pairs_direct(boxes, margin)
    } else {
        pairs_by_tree(boxes, margin)
    }
}

fn finite(b: &BodyBox) -> bool {
    b.lo.iter().chain(b.hi.iter()).all(|v| v.is_finite()) && b.thickness.is_finite()
}

/// A box's (lo, hi) corners.
type Corners = ([f64; 3], [f64; 3]);

/// The inflated box with its corners ordered per axis, as the tree's rectangles and
/// envelopes order them (`from_corners`).
fn ordered(b: &BodyBox, margin: f64) -> Corners {
    let (lo, hi) = b.inflated(margin);
    (
        std::array::from_fn(|d| lo[d].min(hi[d])),
        std::array::from_fn(|d| lo[d].max(hi[d])),
    )
}

/// Every two boxes tested, with the tree's test (closed boxes: touching faces overlap).
pub fn pairs_direct(boxes: &[BodyBox], margin: f64) -> Vec<(u32, u32)> {
    let live: Vec<(u32, Corners)> = boxes
        .iter()
        .filter(|b| finite(b))
        .map(|b| (b.id, ordered(b, margin)))
        .collect();
    let mut pairs = Vec::new();
    for (k, (ia, (alo, ahi))) in live.iter().enumerate() {
        for (ib, (blo, bhi)) in &live[k + 1..] {
            if ia != ib && (0..3).all(|d| alo[d] <= bhi[d] && blo[d] <= ahi[d]) {
                pairs.push(if ia < ib { (*ia, *ib) } else { (*ib, *ia) });
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// The boxes in an R-tree, each searched for the boxes it meets.
pub fn pairs_by_tree(boxes: &[BodyBox], margin: f64) -> Vec<(u32, u32)> {
    let entries: Vec<GeomWithData<Rectangle<[f64; 3]>, u32>> = boxes
        .iter()
        .filter(|b| finite(b))
        .map(|b| {
            let (lo, hi) = b.inflated(margin);
            GeomWithData::new(Rectangle::from_corners(lo, hi), b.id)
        })
        .collect();
    let tree = RTree::bulk_load(entries);
    let mut pairs = Vec::new();
    for b in boxes.iter().filter(|b| finite(b)) {
        let (lo, hi) = b.inflated(margin);
        for hit in tree.locate_in_envelope_intersecting(&AABB::from_corners(lo, hi)) {
            if hit.data > b.id {
                pairs.push((b.id, hit.data));
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(id: u32, x: f64) -> BodyBox {
        BodyBox {
            id,
            lo: Vec3::new(x, 0.0, 0.0),
            hi: Vec3::new(x + 1.0, 1.0, 1.0),
            thickness: 0.1,
        }
    }

    /// Uniform numbers in [0, 1) from a linear congruential generator.
    fn lcg(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn pairs_follow_the_inflated_gap_and_are_sorted() {
        // each box grows by (0.1 + 0.04) / 2, so boxes pair up to a gap of 0.14:
        // 0-1: 0.15 (no), 1-2: 0.05 (yes), 2-3: 0.13 (yes), 3-4: 1.67 (no)
        let boxes = [
            cube(3, 3.33),
            cube(0, 0.0),
            cube(2, 2.2),
            cube(1, 1.15),
            cube(4, 6.0),
        ];
        assert_eq!(candidate_pairs(&boxes, 0.04), vec![(1, 2), (2, 3)]);
        // brute force agrees on a pseudo-random cloud
        let mut rnd = lcg(12345);
        let many: Vec<BodyBox> = (0..80)
            .map(|i| {
                let lo = Vec3::new(6.0 * rnd(), 6.0 * rnd(), 6.0 * rnd());
                BodyBox {
                    id: 200 - 2 * i,
                    lo,
                    hi: lo + Vec3::new(rnd(), rnd(), rnd()),
                    thickness: 0.05,
                }
            })
            .collect();
        let mut brute = Vec::new();
        for a in &many {
            for b in &many {
                let (alo, ahi) = a.inflated(0.2);
                let (blo, bhi) = b.inflated(0.2);
                let overlap = (0..3).all(|d| alo[d] <= bhi[d] && blo[d] <= ahi[d]);
                if a.id < b.id && overlap {
                    brute.push((a.id, b.id));
                }
            }
        }
        brute.sort_unstable();
        assert!(!brute.is_empty());
        assert_eq!(candidate_pairs(&many, 0.2), brute);
    }

    /// The direct test of every two boxes and the tree give the same pairs, on clouds
    /// on both sides of `DIRECT_MAX`, with boxes that only touch, flat and inverted
    /// boxes (negative margin and thickness), repeated ids and non-finite corners.
    #[test]
    fn direct_and_tree_searches_give_the_same_pairs() {
        let mut rnd = lcg(987654321);
        for n in [0usize, 1, 2, 7, 65, DIRECT_MAX, DIRECT_MAX + 1, 300] {
            let mut boxes: Vec<BodyBox> = (0..n)
                .map(|i| {
                    // integer corners: many boxes touch exactly
                    let lo = Vec3::new(
                        (8.0 * rnd()).floor(),
                        (8.0 * rnd()).floor(),
                        (2.0 * rnd()).floor(),
                    );
                    let size = Vec3::new((2.0 * rnd()).floor(), 1.0, (2.0 * rnd()).floor());
                    BodyBox {
                        id: (7 * i as u32) % (n as u32 + 3),
                        lo,
                        hi: lo + size,
                        thickness: if i % 11 == 3 { -0.5 } else { 0.0 },
                    }
                })
                .collect();
            if n > 2 {
                boxes[1].lo.x = f64::NAN;
                boxes[2].hi.z = f64::INFINITY;
            }
            for margin in [0.0, 0.25, -3.0] {
                assert_eq!(
                    pairs_direct(&boxes, margin),
                    pairs_by_tree(&boxes, margin),
                    "{n} boxes, margin {margin}"
                );
            }
        }
    }
}
