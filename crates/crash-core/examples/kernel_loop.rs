//! Runs the element-force stage of a plate repeatedly (for instruction counting with
//! `valgrind --tool=callgrind`, which is repeatable on a busy machine):
//! `kernel_loop [tri|quad|tri-step|quad-step] [cycles] [cells per side]` (`-step`: the
//! whole step, `Group::advance`, instead of the element forces alone) (default 71 for triangles, 100
//! for quads: about 10 000 elements, which stay in cache; the shell_step bench has
//! about 100 000, 224 and 317). Threads: `RAYON_NUM_THREADS` (default all cores);
//! SIMD path: `CRASH_SIMD` (default the best the CPU has).
//!
//! Besides the mean it prints the fastest single cycle: on a loaded machine a cycle
//! (10 000 elements, well under a scheduler time slice) that ran undisturbed is the
//! least noisy time figure available without hardware counters.
//!
//! Diagnostics (docs/performance-history.md, "The quad kernel on AMD Zen 4"): `CRASH_FTZ=1` sets
//! flush-to-zero and denormals-are-zero on every thread; `CRASH_FTZ=flags` clears the
//! MXCSR exception flags on the pool threads and prints them after the run.

use crash_core::shapes::{plate, ElementKind};
use crash_core::{Body, Group, Material, Section, Stabilization, Vec3};

/// Diagnostic: flush denormals to zero (FTZ + DAZ in MXCSR) on every pool thread.
#[allow(unsafe_code, deprecated)]
fn set_ftz() {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: changes only this thread's floating-point control word.
    unsafe {
        use std::arch::x86_64::{_mm_getcsr, _mm_setcsr};
        _mm_setcsr(_mm_getcsr() | 0x8040);
    }
}

/// Diagnostic: clear the sticky exception flags of MXCSR.
#[allow(unsafe_code, deprecated)]
fn clear_flags() {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: changes only this thread's floating-point status word.
    unsafe {
        use std::arch::x86_64::{_mm_getcsr, _mm_setcsr};
        _mm_setcsr(_mm_getcsr() & !0x3f);
    }
}

/// Diagnostic: the sticky exception flags (IE DE ZE OE UE PE) of this thread.
#[allow(unsafe_code, deprecated)]
fn read_flags() -> u32 {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: reads this thread's floating-point status word.
    unsafe {
        std::arch::x86_64::_mm_getcsr() & 0x3f
    }
    #[cfg(not(target_arch = "x86_64"))]
    0
}

fn main() {
    // CRASH_FTZ=1: flush denormals to zero (does the time change?); CRASH_FTZ=flags:
    // report which floating-point exceptions the element loops raised (denormal, NaN)
    let ftz = std::env::var("CRASH_FTZ").unwrap_or_default();
    let flags = ftz == "flags";
    if ftz == "1" || flags {
        let handler = if flags { clear_flags } else { set_ftz };
        handler();
        rayon::ThreadPoolBuilder::new()
            .start_handler(move |_| handler())
            .build_global()
            .expect("pool");
    }
    let mut args = std::env::args().skip(1);
    let what = args.next().unwrap_or_default();
    let kind = if what.starts_with("quad") {
        ElementKind::Quad
    } else {
        ElementKind::Tri
    };
    let whole_step = what.ends_with("-step");
    let cycles: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(20);
    let n = args
        .next()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if kind == ElementKind::Tri { 71 } else { 100 });
    let mat = Material::steel();
    let m = plate(1.0, 1.0, n, n, kind);
    let mut b = Body::new(
        0,
        "plate",
        &m,
        Section::new(mat, 0.002),
        Stabilization::default(),
    )
    .expect("valid body");
    for i in 0..b.state.x.len() {
        let p = b.def.x0[i];
        b.state.v[i] = Vec3::new(0.0, 0.0, 0.1 * (7.0 * p.x).sin() * (5.0 * p.y).cos());
    }
    let n = b.element_count() as f64;
    let mut group = Group::new(vec![b.clone()], Vec3::zeros());
    if whole_step {
        group.start().expect("start");
    }
    let mut e = 0.0;
    let mut clock = crash_core::Clock::default();
    let mut fastest = f64::INFINITY;
    let start = std::time::Instant::now();
    for step in 0..cycles {
        let t = std::time::Instant::now();
        if whole_step {
            group.advance(&clock, 1e-7).expect("step");
            clock = clock.after(1e-7);
            e += group.bodies[0].state.internal_now;
        } else {
            e += b
                .internal_forces(1e-7, step as u64)
                .expect("forces")
                .energy
                .internal;
        }
        fastest = fastest.min(t.elapsed().as_nanos() as f64);
    }
    if flags {
        let f = rayon::broadcast(|_| read_flags());
        println!("MXCSR flags per pool thread (IE=1 DE=2 ZE=4 OE=8 UE=16 PE=32): {f:?}");
    }
    let ns = start.elapsed().as_nanos() as f64 / (cycles as f64 * n);
    println!(
        "{} elements x {cycles} cycles, energy {e:e}, {ns:.1} ns per element-cycle \
         (fastest cycle {:.1}; SIMD path {})",
        n,
        fastest / n,
        crash_core::element::simd::path_name()
    );
}
