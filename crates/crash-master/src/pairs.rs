//! The level-i search of every step, made cheap by temporal coherence (a Verlet list
//! of body pairs).
//!
//! A full search (`crash_core::contact::candidate_pairs`, the contact engine's own
//! broad phase) runs with every box grown by `skin / 2`; it lists every pair that can
//! come within the margin before some box has moved or grown by more than `skin / 2`.
//! Until then each step only re-tests the listed pairs with the exact predicate of the
//! full search (same inflation, same inclusive comparisons), so the pairs returned are
//! exactly those `candidate_pairs(boxes, margin)` returns, at a fraction of its cost.

use crash_core::contact::{candidate_pairs, BodyBox};
use crash_core::Vec3;

/// Rounding allowance on the skin test (boxes are grown and compared in f64).
const SKIN_USE: f64 = 0.45;

#[derive(Debug, Clone)]
pub struct PairSearch {
    margin: f64,
    skin: f64,
    /// Boxes of the last full search (un-grown), in the order given.
    last: Vec<BodyBox>,
    /// Pairs of the last full search with the skin, as positions in `last`, sorted.
    listed: Vec<(u32, u32)>,
    full_searches: u64,
}

fn overlap(a: &BodyBox, b: &BodyBox, margin: f64) -> bool {
    let (alo, ahi) = a.inflated(margin);
    let (blo, bhi) = b.inflated(margin);
    (0..3).all(|d| alo[d] <= bhi[d] && ahi[d] >= blo[d])
}

fn finite(b: &BodyBox) -> bool {
    b.lo.iter().chain(b.hi.iter()).all(|v| v.is_finite()) && b.thickness.is_finite()
}

impl PairSearch {
    /// `margin` as for `candidate_pairs`; `skin` > 0 the extra distance of the list.
    pub fn new(margin: f64, skin: f64) -> Self {
        Self {
            margin,
            skin: skin.max(0.0),
            last: Vec::new(),
            listed: Vec::new(),
            full_searches: 0,
        }
    }

    /// Full searches so far (for benchmarks and diagnostics).
    pub fn full_searches(&self) -> u64 {
        self.full_searches
    }

    /// Pairs (ids, a < b) whose inflated boxes overlap, sorted; identical to
    /// `candidate_pairs(boxes, margin)`.
    pub fn pairs(&mut self, boxes: &[BodyBox]) -> Vec<(u32, u32)> {
        if !self.still_valid(boxes) {
            self.rebuild(boxes);
        }
        let mut out: Vec<(u32, u32)> = self
            .listed
            .iter()
            .filter(|&&(i, j)| {
                let (a, b) = (&boxes[i as usize], &boxes[j as usize]);
                finite(a) && finite(b) && overlap(a, b, self.margin)
            })
            .map(|&(i, j)| {
                let (a, b) = (boxes[i as usize].id, boxes[j as usize].id);
                (a.min(b), a.max(b))
            })
            .collect();
        out.sort_unstable();
        out
    }

    /// Same bodies in the same order, and every box inside its last box grown by the
    /// usable part of half the skin.
    fn still_valid(&self, boxes: &[BodyBox]) -> bool {
        if self.skin <= 0.0 || boxes.len() != self.last.len() {
            return false;
        }
        let s = SKIN_USE * self.skin;
        boxes.iter().zip(&self.last).all(|(b, o)| {
            b.id == o.id
                && b.thickness == o.thickness
                && (0..3).all(|d| b.lo[d] >= o.lo[d] - s && b.hi[d] <= o.hi[d] + s)
        })
    }

    fn rebuild(&mut self, boxes: &[BodyBox]) {
        self.full_searches += 1;
        let g = Vec3::repeat(0.5 * self.skin);
        // ids -> positions, so that the list survives any id numbering
        let grown: Vec<BodyBox> = boxes
            .iter()
            .enumerate()
            .map(|(k, b)| BodyBox {
                id: k as u32,
                lo: b.lo - g,
                hi: b.hi + g,
                thickness: b.thickness,
            })
            .collect();
        self.listed = candidate_pairs(&grown, self.margin);
        self.last = boxes.to_vec();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pseudo-random boxes drifting step by step: the cached search must return exactly
    /// what the full search returns, every step, while searching fully only rarely.
    #[test]
    fn cached_pairs_equal_the_full_search_every_step() {
        let mut seed = 99u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let n = 150;
        let mut boxes: Vec<BodyBox> = (0..n)
            .map(|i| {
                let lo = Vec3::new(8.0 * rnd(), 8.0 * rnd(), 8.0 * rnd());
                BodyBox {
                    id: 1000 - 3 * i as u32,
                    lo,
                    hi: lo + Vec3::new(rnd(), rnd(), rnd()),
                    thickness: 0.02,
                }
            })
            .collect();
        let vel: Vec<Vec3> = (0..n)
            .map(|_| Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 0.02)
            .collect();
        let mut search = PairSearch::new(0.1, 0.2);
        let mut changes = 0;
        let mut prev = Vec::new();
        for step in 0..200 {
            for (b, v) in boxes.iter_mut().zip(&vel) {
                b.lo += v;
                b.hi += v * (1.0 + 0.01 * (step % 3) as f64);
            }
            let got = search.pairs(&boxes);
            assert_eq!(got, candidate_pairs(&boxes, 0.1), "step {step}");
            if got != prev {
                changes += 1;
            }
            prev = got;
        }
        assert!(
            changes > 10,
            "the test scene must change its pairs ({changes})"
        );
        assert!(
            search.full_searches() < 60,
            "{} full searches",
            search.full_searches()
        );
    }
}
