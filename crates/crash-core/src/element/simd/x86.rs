//! The lane types of the three x86-64 paths and their entry points (two of them
//! `#[target_feature]`). See the documentation of `element::simd` for why the intrinsic
//! calls are sound: every `unsafe` block below relies on that one invariant (the CPU
//! has the features of the entry point that instantiated the type; SSE2 always),
//! plus, for stores, on pointers into local `[f64; 8]` arrays or `[f64; 6]` slots,
//! valid for the writes made.

use super::super::real::{Lanes, Real};
use super::Lanewise;
use std::arch::x86_64::*;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

// exactly the features `Path::Avx512.supported()` detects
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,avx,fma")]
pub(super) fn run_avx512<K: Lanewise>(work: K) -> K::Output {
    work.run::<Avx8>()
}

// exactly the features `Path::Avx2.supported()` detects
#[target_feature(enable = "avx2,avx,fma")]
pub(super) fn run_avx2<K: Lanewise>(work: K) -> K::Output {
    work.run::<Avx4>()
}

/// SSE2 is part of x86-64 itself: no detection needed.
pub(super) fn run_baseline<K: Lanewise>(work: K) -> K::Output {
    work.run::<Sse4>()
}

/// Four lanes in two SSE2 registers (the baseline path). SSE2 belongs to every
/// x86-64 CPU, so the intrinsics below are always available.
#[derive(Debug, Clone, Copy)]
struct Sse4([__m128d; 2]);

macro_rules! sse_op {
    ($tr:ident, $f:ident, $op:ident) => {
        impl $tr for Sse4 {
            type Output = Sse4;
            #[inline(always)]
            fn $f(self, o: Sse4) -> Sse4 {
                // SAFETY: SSE2 is in the x86-64 baseline.
                unsafe { Sse4([$op(self.0[0], o.0[0]), $op(self.0[1], o.0[1])]) }
            }
        }
    };
}
sse_op!(Add, add, _mm_add_pd);
sse_op!(Sub, sub, _mm_sub_pd);
sse_op!(Mul, mul, _mm_mul_pd);
sse_op!(Div, div, _mm_div_pd);

impl Neg for Sse4 {
    type Output = Sse4;
    #[inline(always)]
    fn neg(self) -> Sse4 {
        // SAFETY: SSE2 is in the x86-64 baseline.
        unsafe {
            let m = _mm_set1_pd(-0.0);
            Sse4([_mm_xor_pd(self.0[0], m), _mm_xor_pd(self.0[1], m)])
        }
    }
}
impl AddAssign for Sse4 {
    #[inline(always)]
    fn add_assign(&mut self, o: Sse4) {
        *self = *self + o;
    }
}
impl SubAssign for Sse4 {
    #[inline(always)]
    fn sub_assign(&mut self, o: Sse4) {
        *self = *self - o;
    }
}
impl Real for Sse4 {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        // SAFETY: SSE2 is in the x86-64 baseline.
        unsafe { Sse4([_mm_set1_pd(v); 2]) }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: SSE2 is in the x86-64 baseline.
        unsafe { Sse4([_mm_sqrt_pd(self.0[0]), _mm_sqrt_pd(self.0[1])]) }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        // as for Avx4: self where o is NaN (and-not/or blend, SSE2 has no blendv)
        let half = |a: __m128d, b: __m128d| {
            // SAFETY: SSE2 is in the x86-64 baseline.
            unsafe {
                let nan = _mm_cmpunord_pd(b, b);
                let m = _mm_max_pd(a, b);
                _mm_or_pd(_mm_and_pd(nan, a), _mm_andnot_pd(nan, m))
            }
        };
        Sse4([half(self.0[0], o.0[0]), half(self.0[1], o.0[1])])
    }
}
impl Lanes for Sse4 {
    const W: usize = 4;
    #[inline(always)]
    fn from_array(a: [f64; 8]) -> Self {
        // SAFETY: SSE2 is in the x86-64 baseline.
        unsafe { Sse4([_mm_setr_pd(a[0], a[1]), _mm_setr_pd(a[2], a[3])]) }
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 8] {
        let mut a = [0.0; 8];
        // SAFETY: SSE2 is in the x86-64 baseline; a has 8 writable f64.
        unsafe {
            _mm_storeu_pd(a.as_mut_ptr(), self.0[0]);
            _mm_storeu_pd(a.as_mut_ptr().add(2), self.0[1]);
        }
        a
    }
}

macro_rules! lane_type {
    ($name:ident, $v:ty, $w:literal, $set1:ident, $add:ident, $sub:ident, $mul:ident,
     $div:ident, $sqrt:ident, $xor:ident, $max:ident, $load:ident, $store:ident,
     $blend_nan:expr, $quarter:ident, $above:ident) => {
        /// Lanes in one vector register (see the module documentation).
        #[derive(Debug, Clone, Copy)]
        struct $name($v);

        impl Add for $name {
            type Output = $name;
            #[inline(always)]
            fn add(self, o: $name) -> $name {
                // SAFETY: see the module documentation.
                $name(unsafe { $add(self.0, o.0) })
            }
        }
        impl Sub for $name {
            type Output = $name;
            #[inline(always)]
            fn sub(self, o: $name) -> $name {
                // SAFETY: see the module documentation.
                $name(unsafe { $sub(self.0, o.0) })
            }
        }
        impl Mul for $name {
            type Output = $name;
            #[inline(always)]
            fn mul(self, o: $name) -> $name {
                // SAFETY: see the module documentation.
                $name(unsafe { $mul(self.0, o.0) })
            }
        }
        impl Div for $name {
            type Output = $name;
            #[inline(always)]
            fn div(self, o: $name) -> $name {
                // SAFETY: see the module documentation.
                $name(unsafe { $div(self.0, o.0) })
            }
        }
        impl Neg for $name {
            type Output = $name;
            #[inline(always)]
            fn neg(self) -> $name {
                // flips the sign bit, as scalar negation does
                // SAFETY: see the module documentation.
                $name(unsafe { $xor(self.0, $set1(-0.0)) })
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
                // SAFETY: see the module documentation.
                $name(unsafe { $set1(v) })
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                // SAFETY: see the module documentation.
                $name(unsafe { $sqrt(self.0) })
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                // max_pd returns its second operand when either is NaN; f64::max
                // returns the operand that is not NaN: take self where o is NaN.
                // SAFETY: see the module documentation.
                $name(unsafe { $blend_nan($max(self.0, o.0), self.0, o.0) })
            }
        }
        impl Lanes for $name {
            const W: usize = $w;
            #[inline(always)]
            fn from_array(a: [f64; 8]) -> Self {
                // built in registers (a store-and-reload would stall on the
                // store-to-load forwarding of the scalar stores)
                // SAFETY: see the module documentation.
                $name(unsafe { $load(a) })
            }
            #[inline(always)]
            fn to_array(self) -> [f64; 8] {
                let mut a = [0.0; 8];
                // SAFETY: see the module documentation (8 writable f64).
                unsafe { $store(a.as_mut_ptr(), self.0) };
                a
            }
            #[inline(always)]
            fn all_above(self, t: f64, gt: bool) -> bool {
                // SAFETY: see the module documentation.
                unsafe { $above(self.0, t, gt) }
            }
            #[inline(always)]
            fn scatter_rows6(cols: &[Self; 6], rows: &mut [[f64; 6]], first: usize, stride: usize) {
                for k in 0..$w / 4 {
                    // SAFETY: see the module documentation.
                    let t = unsafe { transpose4x6($quarter(cols, k)) };
                    for (j, (lo, hi)) in t.into_iter().enumerate() {
                        let r = &mut rows[first + stride * (4 * k + j)];
                        // SAFETY: see the module documentation; `r` has 6 f64.
                        unsafe { store_row6(r, lo, hi) };
                    }
                }
            }
            #[inline(always)]
            fn stream_rows6<const N: usize>(cols: &[[Self; 6]; N], rows: &mut [[f64; 6]]) {
                // 16-byte non-temporal stores need 16-byte aligned rows: a row is
                // 48 bytes, so every row is when the first one is
                if rows.as_ptr() as usize % 16 != 0 {
                    for (i, c) in cols.iter().enumerate() {
                        Self::scatter_rows6(c, rows, i, N);
                    }
                    return;
                }
                for k in 0..$w / 4 {
                    // SAFETY: see the module documentation.
                    let mut t = unsafe { [[(_mm256_setzero_pd(), _mm_setzero_pd()); 4]; N] };
                    for (i, c) in cols.iter().enumerate() {
                        // SAFETY: see the module documentation.
                        t[i] = unsafe { transpose4x6($quarter(c, k)) };
                    }
                    // lane by lane, each lane's N rows in order: the stores fill
                    // whole lines one after the other (a write-combining buffer
                    // flushed half full costs a read of the line after all)
                    for j in 0..4 {
                        for (i, ti) in t.iter().enumerate() {
                            let (lo, hi) = ti[j];
                            let r = &mut rows[N * (4 * k + j) + i];
                            // SAFETY: see the module documentation; `r` has 6 f64
                            // and is 16-byte aligned (checked above).
                            unsafe { stream_row6(r, lo, hi) };
                        }
                    }
                }
            }
            #[inline(always)]
            fn stream_fence() {
                // SAFETY: SSE is part of x86-64.
                unsafe { _mm_sfence() }
            }
        }
    };
}

#[inline(always)]
unsafe fn from4(a: [f64; 8]) -> __m256d {
    // SAFETY: called only from Avx4 methods (see the module documentation).
    unsafe { _mm256_setr_pd(a[0], a[1], a[2], a[3]) }
}

#[inline(always)]
unsafe fn from8(a: [f64; 8]) -> __m512d {
    // SAFETY: called only from Avx8 methods (see the module documentation).
    unsafe { _mm512_setr_pd(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]) }
}

/// Every lane > t (gt) or >= t; ordered compares, so false for NaN.
#[inline(always)]
unsafe fn above4(v: __m256d, t: f64, gt: bool) -> bool {
    // SAFETY: called only from Avx4 methods (see the module documentation).
    unsafe {
        let t = _mm256_set1_pd(t);
        let m = if gt {
            _mm256_cmp_pd::<_CMP_GT_OQ>(v, t)
        } else {
            _mm256_cmp_pd::<_CMP_GE_OQ>(v, t)
        };
        _mm256_movemask_pd(m) == 0xf
    }
}

/// Every lane > t (gt) or >= t; ordered compares, so false for NaN.
#[inline(always)]
unsafe fn above8(v: __m512d, t: f64, gt: bool) -> bool {
    // SAFETY: called only from Avx8 methods (see the module documentation).
    unsafe {
        let t = _mm512_set1_pd(t);
        let m = if gt {
            _mm512_cmp_pd_mask::<_CMP_GT_OQ>(v, t)
        } else {
            _mm512_cmp_pd_mask::<_CMP_GE_OQ>(v, t)
        };
        m == 0xff
    }
}

/// Lanes 4k..4k+4 of six columns (k = 0 for Avx4).
#[inline(always)]
unsafe fn quarter4(c: &[Avx4; 6], _k: usize) -> [__m256d; 6] {
    [c[0].0, c[1].0, c[2].0, c[3].0, c[4].0, c[5].0]
}

/// Lanes 4k..4k+4 of six columns (k = 0, 1 for Avx8).
#[inline(always)]
unsafe fn quarter8(c: &[Avx8; 6], k: usize) -> [__m256d; 6] {
    // SAFETY: called only from Avx8 methods (see the module documentation).
    unsafe {
        // written out, no `array::map` closure: a closure outside the
        // `#[target_feature]` entry point may not inline the intrinsics (quad.rs,
        // `corner_terms`)
        if k == 0 {
            [
                _mm512_castpd512_pd256(c[0].0),
                _mm512_castpd512_pd256(c[1].0),
                _mm512_castpd512_pd256(c[2].0),
                _mm512_castpd512_pd256(c[3].0),
                _mm512_castpd512_pd256(c[4].0),
                _mm512_castpd512_pd256(c[5].0),
            ]
        } else {
            [
                _mm512_extractf64x4_pd::<1>(c[0].0),
                _mm512_extractf64x4_pd::<1>(c[1].0),
                _mm512_extractf64x4_pd::<1>(c[2].0),
                _mm512_extractf64x4_pd::<1>(c[3].0),
                _mm512_extractf64x4_pd::<1>(c[4].0),
                _mm512_extractf64x4_pd::<1>(c[5].0),
            ]
        }
    }
}

/// Rows of a 4-lane x 6-column block: lane j gets (c0..c3 of lane j, c4 c5 of lane j).
#[inline(always)]
unsafe fn transpose4x6(c: [__m256d; 6]) -> [(__m256d, __m128d); 4] {
    // SAFETY: called only from Avx4/Avx8 methods (see the module documentation).
    unsafe {
        let t0 = _mm256_unpacklo_pd(c[0], c[1]); // a0 b0 a2 b2
        let t1 = _mm256_unpackhi_pd(c[0], c[1]); // a1 b1 a3 b3
        let t2 = _mm256_unpacklo_pd(c[2], c[3]);
        let t3 = _mm256_unpackhi_pd(c[2], c[3]);
        let u0 = _mm256_unpacklo_pd(c[4], c[5]);
        let u1 = _mm256_unpackhi_pd(c[4], c[5]);
        [
            (
                _mm256_permute2f128_pd::<0x20>(t0, t2),
                _mm256_castpd256_pd128(u0),
            ),
            (
                _mm256_permute2f128_pd::<0x20>(t1, t3),
                _mm256_castpd256_pd128(u1),
            ),
            (
                _mm256_permute2f128_pd::<0x31>(t0, t2),
                _mm256_extractf128_pd::<1>(u0),
            ),
            (
                _mm256_permute2f128_pd::<0x31>(t1, t3),
                _mm256_extractf128_pd::<1>(u1),
            ),
        ]
    }
}

/// Store (lo, hi) as the six values of `r`.
#[inline(always)]
unsafe fn store_row6(r: &mut [f64; 6], lo: __m256d, hi: __m128d) {
    let p = r.as_mut_ptr();
    // SAFETY: p points to 6 writable f64: 4 at p, 2 at p + 4; AVX is available
    // (called only from Avx4/Avx8 methods, see the module documentation).
    unsafe {
        _mm256_storeu_pd(p, lo);
        _mm_storeu_pd(p.add(4), hi);
    }
}

/// Store (lo, hi) as the six values of `r` with non-temporal stores (`r` 16-byte
/// aligned).
#[inline(always)]
unsafe fn stream_row6(r: &mut [f64; 6], lo: __m256d, hi: __m128d) {
    let p = r.as_mut_ptr();
    // SAFETY: p points to 6 writable f64, 16-byte aligned (the caller checks); AVX is
    // available (called only from Avx4/Avx8 methods, see the module documentation).
    unsafe {
        _mm_stream_pd(p, _mm256_castpd256_pd128(lo));
        _mm_stream_pd(p.add(2), _mm256_extractf128_pd::<1>(lo));
        _mm_stream_pd(p.add(4), hi);
    }
}

/// r where o is not NaN, s where it is.
#[inline(always)]
unsafe fn keep_if_nan4(r: __m256d, s: __m256d, o: __m256d) -> __m256d {
    // SAFETY: called only from Avx4 methods (see the module documentation).
    unsafe { _mm256_blendv_pd(r, s, _mm256_cmp_pd::<_CMP_UNORD_Q>(o, o)) }
}

/// r where o is not NaN, s where it is.
#[inline(always)]
unsafe fn keep_if_nan8(r: __m512d, s: __m512d, o: __m512d) -> __m512d {
    // SAFETY: called only from Avx8 methods (see the module documentation).
    unsafe { _mm512_mask_blend_pd(_mm512_cmp_pd_mask::<_CMP_UNORD_Q>(o, o), r, s) }
}

lane_type!(
    Avx4,
    __m256d,
    4,
    _mm256_set1_pd,
    _mm256_add_pd,
    _mm256_sub_pd,
    _mm256_mul_pd,
    _mm256_div_pd,
    _mm256_sqrt_pd,
    _mm256_xor_pd,
    _mm256_max_pd,
    from4,
    _mm256_storeu_pd,
    keep_if_nan4,
    quarter4,
    above4
);
lane_type!(
    Avx8,
    __m512d,
    8,
    _mm512_set1_pd,
    _mm512_add_pd,
    _mm512_sub_pd,
    _mm512_mul_pd,
    _mm512_div_pd,
    _mm512_sqrt_pd,
    _mm512_xor_pd,
    _mm512_max_pd,
    from8,
    _mm512_storeu_pd,
    keep_if_nan8,
    quarter8,
    above8
);
