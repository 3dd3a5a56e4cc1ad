//! Compressed blocks of the frame arrays that rarely change (connectivity, offsets,
//! cell types, ids, thickness, placement), kept from one frame to the next: a block
//! whose raw bytes equal the cached block at the same place is not compressed again.
//! On the showcase these arrays are about 40% of a frame's bytes, and compressing them
//! was that share of the background writer's work, which slows the stepping core
//! through the CPU's shared resources (docs/performance-history.md, Output).
//!
//! The raw bytes are compared in full (no hash: a frame must never show another frame's
//! data); memory is capped at `CAP` bytes, blocks beyond it are compressed every time.
//!
//! It also remembers how well each array compressed: float stresses, velocities and
//! resultants shrink little (a Float32 showcase frame at level 2: velocity and M 1.00,
//! von Mises and N 0.89, displacement 0.82, positions 0.75; Float64 at level 1: velocity
//! 0.93, von Mises 0.93, N and M 0.95, displacement 0.78), yet were most of the writer's
//! work. An array whose last measured ratio is at least `POOR` is stored (zlib level 0:
//! the same format, readers see no difference) and measured again every `REMEASURE`
//! frames.

/// Raw plus compressed bytes kept at most.
pub const CAP: usize = 64 << 20;

/// Compressed / raw size at or above which an array is stored, not compressed.
pub const POOR: f64 = 0.9;
/// Frames between two measurements of an array that is stored.
pub const REMEASURE: u64 = 16;

/// Per array (index in `vtu::ARRAYS`), per block index: (raw bytes, compressed bytes);
/// per array, how well it compressed.
#[derive(Debug, Default)]
pub struct BlockCache {
    arrays: Vec<Vec<(Vec<u8>, Vec<u8>)>>,
    bytes: usize,
    /// This frame's (raw, compressed) bytes per array, blocks compressed at full level.
    sizes: Vec<(u64, u64)>,
    /// Arrays stored (level 0) in this frame.
    stored: Vec<bool>,
    frames: u64,
    /// The last frame's in-memory spill, emptied, for the next frame: a fresh one grew
    /// by doubling to a few MB per frame (copies, and new pages the kernel must clear).
    spare: Vec<u8>,
}

impl BlockCache {
    /// zlib level for array `array` in this frame: 0 (stored) if it compressed poorly
    /// when last measured, else `level`.
    pub fn level(&self, array: usize, level: u32) -> u32 {
        if self.stored.get(array).copied().unwrap_or(false) {
            0
        } else {
            level
        }
    }

    /// A block of `array` was compressed from `raw` to `z` bytes at full level.
    pub fn measured(&mut self, array: usize, raw: usize, z: usize) {
        if self.sizes.len() <= array {
            self.sizes.resize(array + 1, (0, 0));
        }
        self.sizes[array].0 += raw as u64;
        self.sizes[array].1 += z as u64;
    }

    /// Keep `buf`'s memory for the next frame (`take_spare`).
    pub fn keep_spare(&mut self, mut buf: Vec<u8>) {
        buf.clear();
        self.spare = buf;
    }

    /// The buffer kept by `keep_spare` (empty), or a new one.
    pub fn take_spare(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.spare)
    }

    /// The frame is written: decide which arrays the next frame stores.
    pub fn end_frame(&mut self) {
        self.frames += 1;
        let remeasure = self.frames.is_multiple_of(REMEASURE);
        self.stored
            .resize(self.sizes.len().max(self.stored.len()), false);
        for (k, &(raw, z)) in self.sizes.iter().enumerate() {
            if raw > 0 {
                self.stored[k] = z as f64 >= POOR * raw as f64;
            }
        }
        if remeasure {
            self.stored.iter_mut().for_each(|s| *s = false);
        }
        self.sizes.iter_mut().for_each(|s| *s = (0, 0));
    }

    /// The compressed form of block `block` of array `array` if its raw bytes are `raw`.
    pub fn get(&self, array: usize, block: usize, raw: &[u8]) -> Option<&[u8]> {
        let (r, z) = self.arrays.get(array)?.get(block)?;
        (r.as_slice() == raw).then_some(z.as_slice())
    }

    /// Remember `z` as the compressed form of `raw` at (`array`, `block`), replacing what
    /// was there, within the cap (blocks are kept in order: a block after a gap is not).
    pub fn put(&mut self, array: usize, block: usize, raw: &[u8], z: &[u8]) {
        if self.arrays.len() <= array {
            self.arrays.resize_with(array + 1, Vec::new);
        }
        let blocks = &mut self.arrays[array];
        let old = blocks.get(block).map_or(0, |(r, z)| r.len() + z.len());
        let new = raw.len() + z.len();
        if block > blocks.len() || self.bytes - old + new > CAP {
            return;
        }
        self.bytes = self.bytes - old + new;
        let entry = (raw.to_vec(), z.to_vec());
        if block == blocks.len() {
            blocks.push(entry);
        } else {
            blocks[block] = entry;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_block_is_reused_only_when_its_raw_bytes_are_equal() {
        let mut c = BlockCache::default();
        c.put(2, 0, b"abc", b"z1");
        assert_eq!(c.get(2, 0, b"abc"), Some(&b"z1"[..]));
        assert_eq!(c.get(2, 0, b"abd"), None);
        assert_eq!(c.get(1, 0, b"abc"), None);
        c.put(2, 0, b"abd", b"z2");
        assert_eq!(c.get(2, 0, b"abc"), None);
        assert_eq!(c.get(2, 0, b"abd"), Some(&b"z2"[..]));
        // a gap is not filled
        c.put(2, 5, b"x", b"y");
        assert_eq!(c.get(2, 5, b"x"), None);
    }

    #[test]
    fn an_array_that_compressed_poorly_is_stored_until_measured_again() {
        let mut c = BlockCache::default();
        c.measured(0, 1000, 950);
        c.measured(1, 1000, 200);
        c.end_frame();
        assert_eq!((c.level(0, 1), c.level(1, 1), c.level(7, 1)), (0, 1, 1));
        // stored arrays are not measured: the decision stands ...
        for _ in 1..REMEASURE - 1 {
            c.end_frame();
            assert_eq!(c.level(0, 1), 0);
        }
        // ... until every REMEASURE-th frame, whose successor compresses again
        c.end_frame();
        assert_eq!(c.level(0, 1), 1);
    }
}
