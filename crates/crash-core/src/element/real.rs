//! Scalar abstraction for the element kernels: the same code runs on one element (`f64`)
//! or on a batch of four or eight elements in SIMD lanes (`F4`, `F8`). Each lane performs
//! exactly the operations the scalar path performs, in the same order, and only IEEE
//! operations that are correctly rounded on every instruction set (+, -, *, /, sqrt,
//! max; Rust never fuses a multiply and an add on its own, so enabling FMA changes no
//! result): batched and scalar results are bit-identical, whatever the SIMD path.

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
    /// `f64::max` lane by lane (a NaN operand yields the other one).
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

macro_rules! lane_type {
    ($(#[$doc:meta])* $name:ident, $w:literal, $align:literal, [$($k:literal)*]) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq)]
        #[repr(C, align($align))]
        pub struct $name(pub [f64; $w]);

        impl Default for $name {
            #[inline(always)]
            fn default() -> Self {
                Self([0.0; $w])
            }
        }

        lane_type!(@op $name, [$($k)*], Add, add, +);
        lane_type!(@op $name, [$($k)*], Sub, sub, -);
        lane_type!(@op $name, [$($k)*], Mul, mul, *);
        lane_type!(@op $name, [$($k)*], Div, div, /);

        impl Neg for $name {
            type Output = $name;
            #[inline(always)]
            fn neg(self) -> $name {
                $name([$(-self.0[$k]),*])
            }
        }

        impl AddAssign for $name {
            #[inline(always)]
            fn add_assign(&mut self, o: $name) {
                *self = *self + o;
            }
        }

        impl SubAssign for $name {
            #[inline(always)]
            fn sub_assign(&mut self, o: $name) {
                *self = *self - o;
            }
        }

        impl Real for $name {
            #[inline(always)]
            fn splat(v: f64) -> Self {
                $name([v; $w])
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                $name([$(self.0[$k].sqrt()),*])
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                $name([$(self.0[$k].max(o.0[$k])),*])
            }
        }

        impl Lanes for $name {
            const W: usize = $w;
            #[inline(always)]
            fn from_array(a: [f64; 8]) -> Self {
                $name([$(a[$k]),*])
            }
            #[inline(always)]
            fn to_array(self) -> [f64; 8] {
                let mut a = [0.0; 8];
                $(a[$k] = self.0[$k];)*
                a
            }
        }
    };
    (@op $name:ident, [$($k:literal)*], $tr:ident, $f:ident, $op:tt) => {
        impl $tr for $name {
            type Output = $name;
            #[inline(always)]
            fn $f(self, o: $name) -> $name {
                $name([$(self.0[$k] $op o.0[$k]),*])
            }
        }
    };
}

lane_type!(
    /// Four lanes of f64 (one element per lane): one AVX2 register, two SSE2 registers.
    F4, 4, 32, [0 1 2 3]
);
lane_type!(
    /// Eight lanes of f64: one AVX-512 register.
    F8, 8, 64, [0 1 2 3 4 5 6 7]
);

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

/// Lanes in and out of a batch (gather before the kernel, scatter after it).
pub trait Lanes: Real {
    /// Elements per batch (at most 8).
    const W: usize;
    /// The first W entries of `a` as lanes.
    fn from_array(a: [f64; 8]) -> Self;
    /// The lanes, in the first W entries.
    fn to_array(self) -> [f64; 8];

    /// Whether every lane is >= t (`gt`: > t); false for a NaN lane.
    #[inline(always)]
    fn all_above(self, t: f64, gt: bool) -> bool {
        let a = self.to_array();
        a[..Self::W]
            .iter()
            .all(|&v| if gt { v > t } else { v >= t })
    }

    /// Six values per lane to six-value rows: `rows[first + stride k][c] = cols[c]` of
    /// lane k, for k < W (a transpose; SIMD types do it in registers).
    #[inline(always)]
    fn scatter_rows6(cols: &[Self; 6], rows: &mut [[f64; 6]], first: usize, stride: usize) {
        let c = [
            cols[0].to_array(),
            cols[1].to_array(),
            cols[2].to_array(),
            cols[3].to_array(),
            cols[4].to_array(),
            cols[5].to_array(),
        ];
        for k in 0..Self::W {
            rows[first + stride * k] = [c[0][k], c[1][k], c[2][k], c[3][k], c[4][k], c[5][k]];
        }
    }

    /// The `N` force rows of each of the W lanes' elements, `rows[N k + i] = cols[i]` of
    /// lane k, written in row order with non-temporal stores where the type has them
    /// (the same values as `scatter_rows6`): whole cache lines go to memory without
    /// first being read, for force slots that would leave the cache before the
    /// integration reads them. Call `stream_fence` before another thread reads them.
    #[inline(always)]
    fn stream_rows6<const N: usize>(cols: &[[Self; 6]; N], rows: &mut [[f64; 6]]) {
        for (i, c) in cols.iter().enumerate() {
            Self::scatter_rows6(c, rows, i, N);
        }
    }

    /// Order this thread's earlier `stream_rows6` stores before its later stores (the
    /// release that hands the rows to another thread).
    #[inline(always)]
    fn stream_fence() {}
}

impl Lanes for f64 {
    const W: usize = 1;
    #[inline(always)]
    fn from_array(a: [f64; 8]) -> Self {
        a[0]
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 8] {
        [self, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    }
}
