//! The largest speed of a body's nodes relative to a few velocities, for the
//! closing-speed rule (`sweep`), without reading every node for every pair: a floor
//! under 64 spheres is in 64 pairs, and a full scan of its nodes per pair took a sixth
//! of such a run.
//!
//! The nodes are taken in chunks of `CHUNK`, each with the box of its velocities
//! (built once per contact pass). For a query u the bound of a chunk is the squared
//! norm of the largest |corner - u| per axis; a chunk whose bounds cannot beat the
//! largest squares found so far is skipped. Rounding is monotone (a larger |x - u|
//! rounds no smaller, and so do its square and the sums), so a skipped node's computed
//! |v - u|^2 is at most its chunk's computed bound; the root of the largest square is
//! the largest root (sqrt is monotone and correctly rounded): the maxima are those of
//! the full scan of norms, bit for bit.

use crate::Vec3;

/// Nodes per velocity box.
pub(crate) const CHUNK: usize = 64;

/// The velocity box of each chunk of `CHUNK` consecutive nodes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpeedBoxes {
    boxes: Vec<(Vec3, Vec3)>,
}

/// The box of the velocities `c` (not empty).
pub(crate) fn velocity_box(c: &[Vec3]) -> (Vec3, Vec3) {
    c.iter().fold((c[0], c[0]), widen)
}

/// The box (lo, hi) grown to hold x (per component min/max: a NaN component is
/// skipped, as `f64::min` skips it).
#[inline]
pub(crate) fn widen((lo, hi): (Vec3, Vec3), x: &Vec3) -> (Vec3, Vec3) {
    (
        Vec3::new(lo.x.min(x.x), lo.y.min(x.y), lo.z.min(x.z)),
        Vec3::new(hi.x.max(x.x), hi.y.max(x.y), hi.z.max(x.z)),
    )
}

impl SpeedBoxes {
    /// The boxes of `v` (min/max only; chunks on the pool, in order: the same boxes).
    pub fn of(v: &[Vec3]) -> Self {
        use rayon::prelude::*;
        let boxes = v
            .par_chunks(CHUNK)
            .with_min_len(super::stage::PAR_CHUNK / CHUNK)
            .map(velocity_box)
            .collect();
        Self { boxes }
    }

    /// Boxes made elsewhere, one per `CHUNK` nodes in node order (`figures.rs`).
    pub(crate) fn from_boxes(boxes: Vec<(Vec3, Vec3)>) -> Self {
        Self { boxes }
    }

    /// Largest |v - u| over `v` (the velocities these boxes were built from): the full
    /// scan's maximum, reading only the chunks that can set it. A body's speed relative
    /// to its own mean is one figure for all of its pairs; the other body's mean is a
    /// query per pair.
    pub fn max_speed(&self, v: &[Vec3], u: &Vec3) -> f64 {
        debug_assert_eq!(self.boxes.len(), v.len().div_ceil(CHUNK));
        // squares throughout, one root at the end: sqrt is monotone and correctly
        // rounded, so the root of the largest square is the largest norm, bit for bit
        let bound = |(lo, hi): &(Vec3, Vec3)| {
            let far = |l: f64, h: f64, u: f64| (l - u).abs().max((h - u).abs());
            Vec3::new(
                far(lo.x, hi.x, u.x),
                far(lo.y, hi.y, u.y),
                far(lo.z, hi.z, u.z),
            )
            .norm_squared()
        };
        let bounds: Vec<f64> = self.boxes.iter().map(bound).collect();
        let scan = |k: usize, m: f64| {
            v[k * CHUNK..((k + 1) * CHUNK).min(v.len())]
                .iter()
                .fold(m, |m, x| m.max((x - u).norm_squared()))
        };
        // the chunk most likely to hold the maximum first, so most others are skipped
        let first = (0..bounds.len()).fold(None, |a: Option<usize>, k| match a {
            Some(j) if bounds[j] >= bounds[k] => Some(j),
            _ => Some(k),
        });
        let mut m = first.map_or(0.0, |k| scan(k, 0.0));
        for (k, &b) in bounds.iter().enumerate() {
            if Some(k) != first && b > m {
                m = scan(k, m);
            }
        }
        m.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn full(v: &[Vec3], u1: &Vec3, u2: &Vec3) -> (f64, f64) {
        v.iter().fold((0.0, 0.0), |(a, b): (f64, f64), x| {
            (a.max((x - u1).norm()), b.max((x - u2).norm()))
        })
    }

    /// A deterministic spread of velocities: most nodes near rest, a few fast, some
    /// chunks nearly uniform (a floor under spheres), and a partial last chunk.
    fn field(n: usize, seed: u64) -> Vec<Vec3> {
        let mut s = seed;
        let mut r = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        (0..n)
            .map(|i| {
                let scale = if i % 97 == 0 {
                    40.0
                } else if i % 7 == 0 {
                    3.0
                } else {
                    1e-3
                };
                Vec3::new(r() * scale, r() * scale, r() * scale - 5.0 * (i % 3) as f64)
            })
            .collect()
    }

    #[test]
    fn chunked_maxima_are_the_full_scans_bit_for_bit() {
        for (n, seed) in [(1, 1), (63, 2), (64, 3), (65, 4), (1000, 5), (10_201, 6)] {
            let v = field(n, seed);
            let boxes = SpeedBoxes::of(&v);
            for u in field(20, seed + 100).chunks(2) {
                let (u1, u2) = (u[0] * 3.0, u[1]);
                let (a, b) = (boxes.max_speed(&v, &u1), boxes.max_speed(&v, &u2));
                let (fa, fb) = full(&v, &u1, &u2);
                assert_eq!((a.to_bits(), b.to_bits()), (fa.to_bits(), fb.to_bits()));
            }
        }
    }

    #[test]
    fn no_nodes_give_zero() {
        let boxes = SpeedBoxes::of(&[]);
        let u = Vec3::new(1.0, 2.0, 3.0);
        assert_eq!(boxes.max_speed(&[], &u), 0.0);
    }
}
