//! The contact stage's figures of a body's nodes, taken in the integration's node loop
//! while each chunk of nodes is still in the cache: the node chunks' boxes and largest
//! speeds (`NodeChunk`, the searches' culling), the velocity boxes (`SpeedBoxes`, the
//! closing speed's maxima), the momentum on its fixed quantum (the mean velocity) and
//! the step's largest move (the tree rebuild's bound, `Surface::refresh_given`).
//!
//! Why: the contact stage read every node of a contact body three more times a step for
//! them (chunk boxes and the skin check, momentum, velocity boxes), after the element
//! stage had pushed the nodes out of the cache. On the showcase that was about 7 of 13
//! ns per element-cycle of the stage on 1 thread, and it hardly scaled on 2: each pass
//! streamed the nodes from memory.
//!
//! Same bits: the boxes are min/max (exact in any grouping), the largest speed is the
//! root of the largest square (sqrt is monotone and correctly rounded, so it is the
//! largest root), the momentum an integer sum; the integration's chunks (`forces::CHUNK`)
//! divide the search's (`NODE_CHUNK`) and contain whole velocity boxes
//! (`speeds::CHUNK`), so every figure covers the nodes it covered before.

use super::speeds::{widen, SpeedBoxes, CHUNK as SPEED_CHUNK};
use super::surface::{NodeChunk, NODE_CHUNK};
use super::sweep::Momentum;
use crate::forces::CHUNK;
use crate::Vec3;

const _: () = assert!(NODE_CHUNK.is_multiple_of(CHUNK) && CHUNK.is_multiple_of(SPEED_CHUNK));

/// Velocity boxes per integration chunk.
const BOXES: usize = CHUNK / SPEED_CHUNK;

/// The figures of one integration chunk.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ChunkFigures {
    lo: Vec3,
    hi: Vec3,
    /// Largest |v|^2.
    vmax2: f64,
    momentum: Momentum,
    boxes: [(Vec3, Vec3); BOXES],
    count: usize,
}

impl ChunkFigures {
    /// The figures of nodes with new positions boxed in (lo, hi), velocities `v` and
    /// masses `m`, on the body's momentum scale.
    pub(crate) fn of(lo: Vec3, hi: Vec3, v: &[Vec3], m: &[f64], scale: f64) -> Self {
        // one pass over the chunk for the three figures (each the same bits as its own
        // pass: min/max, the largest square, an integer sum)
        let mut boxes = [(Vec3::zeros(), Vec3::zeros()); BOXES];
        let mut count = 0;
        let mut vmax2 = 0.0f64;
        let mut p = [0i64; 3];
        for ((b, c), mc) in boxes
            .iter_mut()
            .zip(v.chunks(SPEED_CHUNK))
            .zip(m.chunks(SPEED_CHUNK))
        {
            let mut bx = (c[0], c[0]);
            for (x, &mi) in c.iter().zip(mc) {
                bx = widen(bx, x);
                vmax2 = vmax2.max(x.norm_squared());
                for d in 0..3 {
                    p[d] = p[d].wrapping_add(Momentum::term(mi, x[d], scale));
                }
            }
            *b = bx;
            count += 1;
        }
        Self {
            lo,
            hi,
            vmax2,
            momentum: Momentum(p),
            boxes,
            count,
        }
    }
}

/// A contact body's figures after one integration step.
#[derive(Debug, Clone)]
pub struct NodeFigures {
    pub(crate) chunks: Vec<NodeChunk>,
    pub(crate) speeds: SpeedBoxes,
    pub(crate) momentum: Momentum,
    /// The body's total mass and momentum scale (`Momentum::scale`).
    pub(crate) mass: f64,
    pub(crate) scale: f64,
    /// Bound on any node's move in the step: the largest |h v| plus the rounding of
    /// x + h v.
    pub(crate) max_move: f64,
}

impl NodeFigures {
    /// The body's figures from its chunks' (in node order).
    pub(crate) fn gather(
        parts: &[ChunkFigures],
        mass: f64,
        scale: f64,
        max_move: f64,
        (lo, hi): (Vec3, Vec3),
    ) -> Self {
        let chunks = parts
            .chunks(NODE_CHUNK / CHUNK)
            .map(|g| {
                let (lo, hi, v2) = g.iter().fold(
                    (
                        Vec3::repeat(f64::INFINITY),
                        Vec3::repeat(f64::NEG_INFINITY),
                        0.0,
                    ),
                    |(lo, hi, v2): (Vec3, Vec3, f64), c| {
                        (lo.inf(&c.lo), hi.sup(&c.hi), v2.max(c.vmax2))
                    },
                );
                NodeChunk {
                    lo,
                    hi,
                    vmax: v2.sqrt(),
                }
            })
            .collect();
        let boxes = parts
            .iter()
            .flat_map(|c| c.boxes[..c.count].iter().copied())
            .collect();
        let momentum = parts
            .iter()
            .fold(Momentum::default(), |a, c| a + c.momentum);
        // x + h v rounds by at most half an ulp of the largest coordinate
        let reach = lo.abs().max().max(hi.abs().max());
        Self {
            chunks,
            speeds: SpeedBoxes::from_boxes(boxes),
            momentum,
            mass,
            scale,
            max_move: max_move + 4.0 * f64::EPSILON * reach,
        }
    }

    /// The mass-weighted mean velocity (`sweep::mean_velocity`'s bits).
    pub(crate) fn mean(&self) -> Vec3 {
        self.momentum.mean(self.mass, self.scale)
    }
}
