//! Run-time choice of the instruction set for the element loops (and the integration's
//! node loop, `node_loop.rs`, which uses no lanes but gains registers and encodings), so
//! that one binary runs on every x86-64 and uses what the CPU has:
//!
//! | path       | lanes per batch          | target features                                   |
//! | ---------- | ------------------------ | ------------------------------------------------- |
//! | `avx512`   | 8 (`Avx8`, one zmm)      | AVX-512 F/VL/DQ/BW + AVX2 + FMA (x86-64-v4 level) |
//! | `avx2`     | 4 (`Avx4`, one ymm)      | AVX + AVX2 + FMA (x86-64-v3 level)                |
//! | `baseline` | 4 (`Sse4`, two xmm)      | none beyond x86-64's own SSE2                     |
//!
//! The kernels are generic (`Real`, `Lanes`) and `#[inline(always)]`; each path is one
//! `#[target_feature]` function that instantiates them with its lane type, so the
//! compiler generates the same source three times for three instruction sets. `Sse4`,
//! `Avx4` and `Avx8` wrap `__m128d` pairs, `__m256d` and `__m512d` and do their
//! arithmetic with `core::arch` intrinsics: every operation is one vector instruction
//! whatever the size of the kernel (plain `[f64; N]` lanes rely on the compiler's SLP
//! vectorizer, which gave up on parts of the triangle kernel after unrelated edits, and
//! under AVX-512 features turned lane gathers into slow `vgatherqpd`).
//!
//! Every path gives the same bits: the kernels use only correctly rounded IEEE
//! operations (+, -, *, /, sqrt, max, negation), element by element in the same order,
//! and never a fused multiply-add (Rust does not contract `a * b + c`, and no FMA
//! intrinsic is used). `tests/simd_paths.rs` checks this on every path the machine has.
//!
//! Unsafe code: this module and its `x86` submodule only (`#[allow(unsafe_code)]` on the
//! items that need it).
//! The intrinsics need AVX2 / AVX-512; calling them is sound because `Avx4` and `Avx8`
//! are private to this module and instantiated only in `run_avx2` / `run_avx512`, which
//! `dispatch` calls only after `Path::supported` detected every feature they enable; so a
//! value of these types exists only on a CPU that has them. `Sse4` needs SSE2, which
//! every x86-64 CPU has. On other architectures the baseline path runs `F4` (plain
//! arrays, no unsafe code).
//!
//! The path is detected once (`is_x86_feature_detected!`). `CRASH_SIMD=baseline|avx2|
//! avx512|auto` in the environment, read at that moment, or [`force`] overrides it; a
//! path the CPU lacks is never taken.

use super::real::Lanes;
#[cfg(not(target_arch = "x86_64"))]
use super::real::F4;
use std::sync::atomic::{AtomicU8, Ordering};

/// An instruction-set path of the element kernels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Path {
    Baseline,
    Avx2,
    Avx512,
}

impl Path {
    /// Every path, slowest first.
    pub const ALL: [Path; 3] = [Path::Baseline, Path::Avx2, Path::Avx512];

    /// "baseline", "avx2" or "avx512".
    pub fn name(self) -> &'static str {
        match self {
            Path::Baseline => "baseline",
            Path::Avx2 => "avx2",
            Path::Avx512 => "avx512",
        }
    }

    /// Parse a name as written by [`Path::name`].
    pub fn from_name(s: &str) -> Option<Path> {
        Path::ALL.into_iter().find(|p| p.name() == s)
    }

    /// Elements per SIMD batch on this path.
    pub fn lanes(self) -> usize {
        match self {
            Path::Avx512 => 8,
            _ => 4,
        }
    }

    /// Whether this CPU (and OS) can run the path: every feature its entry point
    /// enables (`x86::run_avx2`, `x86::run_avx512`) is detected.
    pub fn supported(self) -> bool {
        match self {
            Path::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            Path::Avx2 => {
                is_x86_feature_detected!("avx")
                    && is_x86_feature_detected!("avx2")
                    && is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            Path::Avx512 => {
                Path::Avx2.supported()
                    && is_x86_feature_detected!("avx512f")
                    && is_x86_feature_detected!("avx512vl")
                    && is_x86_feature_detected!("avx512dq")
                    && is_x86_feature_detected!("avx512bw")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    fn code(self) -> u8 {
        match self {
            Path::Baseline => 1,
            Path::Avx2 => 2,
            Path::Avx512 => 3,
        }
    }
}

/// The fastest path this CPU supports.
pub fn best() -> Path {
    Path::ALL
        .into_iter()
        .rev()
        .find(|p| p.supported())
        .unwrap_or(Path::Baseline)
}

/// The paths this CPU supports, slowest first.
pub fn available() -> Vec<Path> {
    Path::ALL.into_iter().filter(|p| p.supported()).collect()
}

/// The path in use: 0 = not chosen yet, else `Path::code`. Invariant: a non-zero value
/// is always a path whose `supported()` returned true (what makes `dispatch` sound).
static CURRENT: AtomicU8 = AtomicU8::new(0);

/// The path the element loops use (chosen on first call: `CRASH_SIMD`, else the best).
pub fn path() -> Path {
    match CURRENT.load(Ordering::Relaxed) {
        1 => Path::Baseline,
        2 => Path::Avx2,
        3 => Path::Avx512,
        _ => {
            let p = from_env();
            CURRENT.store(p.code(), Ordering::Relaxed);
            p
        }
    }
}

/// Name of the path in use: "avx512", "avx2" or "baseline" (for the run's log and
/// summary).
pub fn path_name() -> &'static str {
    path().name()
}

/// The path `CRASH_SIMD` asks for, if this CPU supports it; otherwise the best one.
fn from_env() -> Path {
    let Ok(v) = std::env::var("CRASH_SIMD") else {
        return best();
    };
    let v = v.trim().to_ascii_lowercase();
    if v.is_empty() || v == "auto" {
        return best();
    }
    match Path::from_name(&v) {
        Some(p) if p.supported() => p,
        Some(p) => {
            tracing::warn!(
                "CRASH_SIMD={v}: this CPU lacks {}; using {}",
                p.name(),
                best().name()
            );
            best()
        }
        None => {
            tracing::warn!(
                "CRASH_SIMD={v} is not one of auto, baseline, avx2, avx512; using {}",
                best().name()
            );
            best()
        }
    }
}

/// A path this CPU cannot run was requested.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unsupported(pub Path);

impl std::fmt::Display for Unsupported {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "this CPU does not support the {} path", self.0.name())
    }
}

impl std::error::Error for Unsupported {}

/// Use `p` from now on (every thread). Results do not depend on the path; this is for
/// tests and measurements.
pub fn force(p: Path) -> Result<(), Unsupported> {
    if !p.supported() {
        return Err(Unsupported(p));
    }
    CURRENT.store(p.code(), Ordering::Relaxed);
    Ok(())
}

/// Work that runs with any lane type: an element loop (or a chunk of the node loop),
/// instantiated once per path.
pub trait Lanewise {
    type Output;
    /// Run with batches of `S::W` elements (and the remainder one by one).
    fn run<S: Lanes>(self) -> Self::Output;
}

/// Ask the CPU to bring the cache line of `r` in ahead of its use (a hint: no effect on
/// any value). The node loop of the integration reads each node's element force slots,
/// which lie wherever the node's elements are in element order: issued a few nodes
/// ahead, the loads overlap instead of stalling one by one.
#[inline(always)]
#[allow(unsafe_code)]
pub fn prefetch<T>(r: &T) {
    // SAFETY: a prefetch never faults and changes no memory; SSE is part of x86-64.
    #[cfg(target_arch = "x86_64")]
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>((r as *const T).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = r;
}

/// Run `work` on the current path.
#[inline]
#[allow(unsafe_code)]
pub fn dispatch<K: Lanewise>(work: K) -> K::Output {
    match path() {
        // SAFETY: `path()` returns Avx512 or Avx2 only if `Path::supported` detected
        // every target feature the called function enables (invariant of `CURRENT`).
        #[cfg(target_arch = "x86_64")]
        Path::Avx512 => unsafe { x86::run_avx512(work) },
        #[cfg(target_arch = "x86_64")]
        Path::Avx2 => unsafe { x86::run_avx2(work) },
        #[cfg(target_arch = "x86_64")]
        Path::Baseline => x86::run_baseline(work),
        #[cfg(not(target_arch = "x86_64"))]
        _ => work.run::<F4>(),
    }
}

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod x86;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_baseline_is_always_available() {
        for p in Path::ALL {
            assert_eq!(Path::from_name(p.name()), Some(p));
        }
        assert!(available().contains(&Path::Baseline));
        assert!(best().supported());
    }
}
