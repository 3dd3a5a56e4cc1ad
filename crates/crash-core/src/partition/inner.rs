//! Element chunks computed while the halo travels (the direct halo exchange, protocol
//! v18): between a holder's integration and its element forces, the chunks of its
//! parts whose elements read only owned nodes need nothing from the other holders.

use super::SharedGroup;
use crate::clock::Clock;
use crate::element::batch::ChunkResult;

/// Element chunks computed before the halo arrived: the step they are for, and each
/// chunk's result (None: not yet computed).
pub(super) type Early = (u64, Vec<Option<ChunkResult>>);

impl SharedGroup {
    /// Between phases 1 and 2, while the other holders' states travel (the direct halo
    /// exchange): the element chunks of the parts computed here that read only their
    /// owned nodes, for the step of length h from `clock`. `forces` computes the rest
    /// and sums every chunk in order: the same bits as computing them all there.
    /// Returns how many chunks it computed.
    pub fn inner_forces(&mut self, clock: &Clock, h: f64) -> usize {
        let step = clock.after(h).step;
        let mut count = 0;
        for (i, s) in self.split.splits.iter_mut().enumerate() {
            for (q, p) in s.parts.iter_mut().enumerate() {
                if !self.split.mine[i][q] {
                    continue;
                }
                let mut done = p.body.no_chunks();
                p.body.element_chunks(h, &mut done, Some(&self.inner[i][q]));
                count += done.iter().flatten().count();
                self.early[i][q] = Some((step, done));
            }
        }
        count
    }
}
