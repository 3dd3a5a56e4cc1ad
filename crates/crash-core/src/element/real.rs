//! Scalar abstraction for the element kernels: the same code runs on one element (`f64`)
//! or on a batch of four elements in SIMD lanes (`F4`). Each lane performs exactly the
//! operations the scalar path performs, in the same order (Rust never fuses multiply-adds
//! on its own), so batched and scalar results are bit-identical.

use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
{
    fn splat(v: f64) -> Self;
    fn sqrt(self) -> Self;
    fn max(self, o: Self) -> Self;
}

impl Real for f64 {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f64::max(self, o)
    }
}

/// Four lanes of f64 (one element per lane).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[repr(align(32))]
pub struct F4(pub [f64; 4]);

macro_rules! lanewise {
    ($tr:ident, $f:ident, $op:tt) => {
        impl $tr for F4 {
            type Output = F4;
            #[inline(always)]
            fn $f(self, o: F4) -> F4 {
                F4([self.0[0] $op o.0[0], self.0[1] $op o.0[1], self.0[2] $op o.0[2], self.0[3] $op o.0[3]])
            }
        }
    };
}
lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
lanewise!(Div, div, /);

impl Neg for F4 {
    type Output = F4;
    #[inline(always)]
    fn neg(self) -> F4 {
        F4([-self.0[0], -self.0[1], -self.0[2], -self.0[3]])
    }
}

impl AddAssign for F4 {
    #[inline(always)]
    fn add_assign(&mut self, o: F4) {
        *self = *self + o;
    }
}

impl SubAssign for F4 {
    #[inline(always)]
    fn sub_assign(&mut self, o: F4) {
        *self = *self - o;
    }
}

impl Real for F4 {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        F4([v; 4])
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F4(self.0.map(f64::sqrt))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        F4([
            self.0[0].max(o.0[0]),
            self.0[1].max(o.0[1]),
            self.0[2].max(o.0[2]),
            self.0[3].max(o.0[3]),
        ])
    }
}

/// A 3-vector of scalars or lanes.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct V3<S> {
    pub x: S,
    pub y: S,
    pub z: S,
}

impl<S: Real> V3<S> {
    #[inline(always)]
    pub fn new(x: S, y: S, z: S) -> Self {
        Self { x, y, z }
    }
    #[inline(always)]
    pub fn zero() -> Self {
        let z = S::splat(0.0);
        Self { x: z, y: z, z }
    }
    #[inline(always)]
    pub fn plus(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
    #[inline(always)]
    pub fn minus(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
    #[inline(always)]
    pub fn scale(self, s: S) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
    #[inline(always)]
    pub fn dot(self, o: Self) -> S {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    #[inline(always)]
    pub fn norm_squared(self) -> S {
        self.dot(self)
    }
}

/// Lane `k` of a value (for scatter after a batch).
pub trait Lanes: Real {
    const W: usize;
    fn lane(self, k: usize) -> f64;
    fn set_lane(&mut self, k: usize, v: f64);
}

impl Lanes for f64 {
    const W: usize = 1;
    #[inline(always)]
    fn lane(self, _k: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn set_lane(&mut self, _k: usize, v: f64) {
        *self = v;
    }
}

impl Lanes for F4 {
    const W: usize = 4;
    #[inline(always)]
    fn lane(self, k: usize) -> f64 {
        self.0[k]
    }
    #[inline(always)]
    fn set_lane(&mut self, k: usize, v: f64) {
        self.0[k] = v;
    }
}
