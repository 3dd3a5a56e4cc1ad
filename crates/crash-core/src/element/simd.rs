//! Run-time choice of the instruction set for the element loops, so that one binary
//! runs on every x86-64 and uses what the CPU has:
//!
//! | path       | lanes per batch  | target features                                  |
//! | ---------- | ---------------- | ------------------------------------------------ |
//! | `avx512`   | 4 (`F4`, ymm)    | AVX-512 F/VL/DQ/BW + AVX2 + FMA (x86-64-v4 level) |
//! | `avx2`     | 4 (`F4`, ymm)    | AVX2 + FMA + BMI1/2 (x86-64-v3 level)            |
//! | `baseline` | 4 (`F4`, 2 xmm)  | none beyond the target's (SSE2 on x86-64)        |
//!
//! The kernels are generic (`Real`, `Lanes`) and `#[inline(always)]`; each path is one
//! `#[target_feature]` function that instantiates them, so the compiler generates the
//! same source three times for three instruction sets. Every path gives the same bits:
//! the kernels use only correctly rounded IEEE operations, element by element in the
//! same order, and never a fused multiply-add (Rust does not contract `a * b + c`).
//! `tests/simd_paths.rs` checks this on every path the machine has.
//!
//! The path is detected once (`is_x86_feature_detected!`). `CRASH_SIMD=baseline|avx2|
//! avx512|auto` in the environment, read at that moment, or [`force`] overrides it; a
//! path the CPU lacks is never taken.

use super::real::{Lanes, F4};
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
        4
    }

    /// Whether this CPU (and OS) can run the path.
    pub fn supported(self) -> bool {
        match self {
            Path::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            Path::Avx2 => {
                is_x86_feature_detected!("avx2")
                    && is_x86_feature_detected!("fma")
                    && is_x86_feature_detected!("bmi1")
                    && is_x86_feature_detected!("bmi2")
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

/// Work that runs with any lane type: an element loop, instantiated once per path.
pub trait Lanewise {
    type Output;
    /// Run with batches of `S::W` elements (and the remainder one by one).
    fn run<S: Lanes>(self) -> Self::Output;
}

/// Run `work` on the current path.
#[inline]
#[allow(unsafe_code)]
pub fn dispatch<K: Lanewise>(work: K) -> K::Output {
    match path() {
        // SAFETY: `path()` returns Avx512 or Avx2 only if `Path::supported` detected
        // every target feature the called function enables (invariant of `CURRENT`).
        #[cfg(target_arch = "x86_64")]
        Path::Avx512 => unsafe { run_avx512(work) },
        #[cfg(target_arch = "x86_64")]
        Path::Avx2 => unsafe { run_avx2(work) },
        _ => work.run::<F4>(),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,avx,fma,bmi1,bmi2,sse4.2,popcnt")]
fn run_avx512<K: Lanewise>(work: K) -> K::Output {
    work.run::<F4>()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx,fma,bmi1,bmi2,sse4.2,popcnt")]
fn run_avx2<K: Lanewise>(work: K) -> K::Output {
    work.run::<F4>()
}

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
