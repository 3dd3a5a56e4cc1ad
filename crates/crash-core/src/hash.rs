//! Bitwise state hash (FNV-1a over the exact f64 bits) used to prove determinism.

use crate::body::Body;
use crate::Vec3;

const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const PRIME: u64 = 0x0000_0100_0000_01b3;

#[derive(Debug, Clone, Copy)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Self(OFFSET)
    }
}

impl Fnv {
    pub fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(PRIME);
        }
    }
    pub fn f64(&mut self, v: f64) {
        self.bytes(&v.to_bits().to_le_bytes());
    }
    pub fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// Hash of positions, velocities and angular velocities of the bodies, in the order
/// given (callers pass bodies sorted by id).
pub fn state_hash<'a>(bodies: impl IntoIterator<Item = &'a Body>) -> u64 {
    state_hash_of(
        bodies
            .into_iter()
            .map(|b| (b.def.id, &b.state.x[..], &b.state.v[..], &b.state.w[..])),
    )
}

/// The same hash from the parts of each body (id, x, v, w), e.g. of an output frame.
pub fn state_hash_of<'a>(
    bodies: impl IntoIterator<Item = (u32, &'a [Vec3], &'a [Vec3], &'a [Vec3])>,
) -> u64 {
    let mut h = StateHasher::default();
    for (id, x, v, w) in bodies {
        h.add(id, x, v, w);
    }
    h.finish()
}

/// The state hash fed one body at a time (in id order), e.g. while a frame streams by.
#[derive(Debug, Clone, Copy, Default)]
pub struct StateHasher(Fnv);

impl StateHasher {
    pub fn add(&mut self, id: u32, x: &[Vec3], v: &[Vec3], w: &[Vec3]) {
        let h = &mut self.0;
        h.u64(id as u64);
        for i in 0..x.len() {
            for d in 0..3 {
                h.f64(x[i][d]);
                h.f64(v[i][d]);
                h.f64(w[i][d]);
            }
        }
    }

    pub fn finish(&self) -> u64 {
        self.0.finish()
    }
}
