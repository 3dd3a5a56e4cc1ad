//! One binary, every instruction set: the element loops give the same bits on every SIMD
//! path this CPU has (baseline, AVX2, AVX-512: `element::simd`), and in SIMD batches of
//! 4 or 8 elements the same bits as one element at a time.

use crash_core::element::batch::{QuadChunk, TriChunk};
use crash_core::element::real::{F4, F8};
use crash_core::element::simd::{self, Lanewise, Path};
use crash_core::hash::state_hash;
use crash_core::shapes::{plate, ElementKind};
use crash_core::{Body, Group, Material, Run, RunConfig, Section, Stabilization, Vec3};
use std::sync::Mutex;

/// Tests that force SIMD paths take this lock (the path is process-wide).
static FORCING: Mutex<()> = Mutex::new(());

/// Triangles and quads, with and without Kelvin damping, element counts that leave a
/// remainder after the SIMD batches, a distorted mesh and a velocity field with spin.
/// Polynomials only (no sin/cos: libm picks its implementation by CPU, and its last
/// bit may differ between them), so the hash can be compared across machines: the
/// same binary under `qemu-x86_64 -cpu Nehalem` (baseline path only) must print the
/// same hash as here.
fn scene() -> Vec<Body> {
    let mut out = Vec::new();
    let cases = [
        (ElementKind::Tri, 1e-7, 19, 13),
        (ElementKind::Quad, 1e-7, 21, 13),
        (ElementKind::Quad, 0.0, 37, 29),
        (ElementKind::Tri, 0.0, 11, 7),
    ];
    for (id, (kind, kelvin, nx, ny)) in cases.into_iter().enumerate() {
        let mat = Material::new(7800.0, 200e9, 0.3, kelvin).expect("valid");
        let mut m = plate(0.4, 0.3, nx, ny, kind);
        for p in &mut m.nodes {
            let (x, y) = (p.x, p.y);
            p.x += 0.02 * y * (0.09 - y * y);
            p.y += 0.02 * x * (0.16 - x * x);
            p.z += 0.01 * id as f64 + 0.01 * x * (0.04 - x * x);
        }
        let mut b = Body::new(
            id as u32,
            "p",
            &m,
            Section::new(mat, 0.002),
            Stabilization::default(),
        )
        .expect("valid");
        for i in 0..b.state.x.len() {
            let p = b.def.x0[i];
            let bump = 50.0 * (0.04 - p.x * p.x) * (0.0225 - p.y * p.y) / 0.0009;
            b.state.v[i] = Vec3::new(0.3 * p.y, -0.2 * p.x, 2.0 * bump * p.x / 0.2);
            b.state.w[i] = Vec3::new(3.0 * p.y, 1.0, -2.0 * p.x);
        }
        out.push(b);
    }
    out
}

fn final_hash() -> u64 {
    let mut run = Run::new(
        Group::new(scene(), Vec3::new(0.0, 0.0, -9.81)),
        RunConfig {
            end_time: f64::INFINITY,
            ..Default::default()
        },
    )
    .expect("start");
    for _ in 0..200 {
        run.step().expect("stable");
    }
    state_hash(&run.group.bodies)
}

#[test]
fn every_simd_path_gives_the_same_state_hash() {
    let _one_at_a_time = FORCING.lock().unwrap_or_else(|e| e.into_inner());
    let paths = simd::available();
    println!(
        "paths on this CPU: {:?} (auto: {})",
        paths.iter().map(|p| p.name()).collect::<Vec<_>>(),
        simd::best().name()
    );
    let mut hashes = Vec::new();
    for p in &paths {
        simd::force(*p).expect("available path");
        assert_eq!(simd::path_name(), p.name());
        let h = final_hash();
        println!("{}: state hash {h:016x}", p.name());
        hashes.push(h);
    }
    assert!(hashes.windows(2).all(|w| w[0] == w[1]), "{hashes:x?}");
    if let Ok(want) = std::env::var("CRASH_EXPECT_HASH") {
        assert_eq!(
            format!("{:016x}", hashes[0]),
            want,
            "hash of another machine"
        );
    }
    for p in Path::ALL {
        assert_eq!(simd::force(p).is_ok(), p.supported());
    }
    simd::force(simd::best()).expect("best path");
}

/// How a body's element loops run: one lane type, or the current SIMD path.
trait Runner {
    fn tri(c: TriChunk<'_>) -> crash_core::element::batch::ChunkResult;
    fn quad(c: QuadChunk<'_>) -> crash_core::element::batch::ChunkResult;
}

impl<S: crash_core::element::real::Lanes> Runner for S {
    fn tri(c: TriChunk<'_>) -> crash_core::element::batch::ChunkResult {
        c.run::<S>()
    }
    fn quad(c: QuadChunk<'_>) -> crash_core::element::batch::ChunkResult {
        c.run::<S>()
    }
}

/// The path chosen by `simd::force` (its own lane type: Sse4, Avx4 or Avx8).
struct Dispatched;

impl Runner for Dispatched {
    fn tri(c: TriChunk<'_>) -> crash_core::element::batch::ChunkResult {
        simd::dispatch(c)
    }
    fn quad(c: QuadChunk<'_>) -> crash_core::element::batch::ChunkResult {
        simd::dispatch(c)
    }
}

/// Internal forces of one body with batches of `S::W` elements (and the remainder one by
/// one), compared bit for bit.
fn forces_with<S: Runner>(b: &Body) -> (Vec<u64>, Vec<u64>) {
    let mut b = b.clone();
    let (sec, stab) = (b.def.section, b.def.stab);
    let nodes = (&b.state.x[..], &b.state.v[..], &b.state.w[..]);
    let nt = b.def.tris.len();
    let ns = b.def.gather_slot.len();
    // the forces, then (a damped body) the Kelvin part of each
    let (slots, kelvin) = b.state.slots.split_at_mut(ns);
    let (ts, qs) = slots.split_at_mut(3 * nt);
    let (tk, qk) = kelvin.split_at_mut(if kelvin.is_empty() { 0 } else { 3 * nt });
    let (tst, qst) = b.state.shell.split_at_mut(nt);
    let mut sums = Vec::new();
    // the last pass writes the slots with non-temporal stores (`forces::stream_slots`):
    // what it leaves in them is compared like the rest
    for pass in 0..3 {
        let s = S::tri(TriChunk {
            sec: &sec,
            stab: &stab,
            els: &b.def.tris,
            states: &mut *tst,
            slots: &mut *ts,
            damped: &mut *tk,
            nodes,
            h: 1e-6,
            first: 0,
            uncounted: &None,
            stream: pass == 2,
        })
        .expect("forces");
        let q = S::quad(QuadChunk {
            sec: &sec,
            stab: &stab,
            els: &b.def.quads,
            states: &mut *qst,
            hourglass: &mut b.state.hourglass,
            slots: &mut *qs,
            damped: &mut *qk,
            nodes,
            h: 1e-6,
            first: nt,
            uncounted: &None,
            stream: pass == 2,
        })
        .expect("forces");
        for s in [s, q] {
            let e = s.energy;
            sums.extend([e.internal, e.hourglass, s.dt, s.hot_density]);
        }
    }
    let mut bits: Vec<u64> = b
        .state
        .slots
        .iter()
        .flatten()
        .map(|v| v.to_bits())
        .collect();
    bits.extend(
        b.state
            .shell
            .iter()
            .flat_map(|s| s.m.into_iter().chain(s.q).chain([s.drill]))
            .map(f64::to_bits),
    );
    bits.extend(
        b.state
            .hourglass
            .iter()
            .flat_map(|h| [h.w, h.th[0], h.th[1]])
            .map(f64::to_bits),
    );
    (bits, sums.into_iter().map(f64::to_bits).collect())
}

#[test]
fn batches_of_4_and_8_match_one_element_at_a_time() {
    let _one_at_a_time = FORCING.lock().unwrap_or_else(|e| e.into_inner());
    for b in scene() {
        let one = forces_with::<f64>(&b);
        assert_eq!(one, forces_with::<F4>(&b), "F4, body {}", b.def.id);
        assert_eq!(one, forces_with::<F8>(&b), "F8, body {}", b.def.id);
        // the intrinsic lane types of every path this CPU has (the chunk is the whole
        // body here, so W = 4 and W = 8 leave different remainders)
        for p in simd::available() {
            simd::force(p).expect("available");
            assert_eq!(
                one,
                forces_with::<Dispatched>(&b),
                "{}, body {}",
                p.name(),
                b.def.id
            );
        }
    }
    simd::force(simd::best()).expect("best path");
}

/// The baseline path on an emulated CPU without SSE3/AVX (Nehalem: SSE4.2 at most), if
/// `qemu-x86_64` is installed (`apt-get install qemu-user`): no SIGILL, and the state
/// hash of this machine. Skipped (with a message) without qemu.
#[test]
fn an_old_cpu_under_qemu_runs_the_baseline_path_to_the_same_hash() {
    if std::env::var("CRASH_EXPECT_HASH").is_ok() {
        return; // this is the emulated run itself
    }
    let qemu = std::process::Command::new("qemu-x86_64")
        .arg("--version")
        .output();
    if !qemu.is_ok_and(|o| o.status.success()) {
        println!("skipped: qemu-x86_64 is not installed");
        return;
    }
    let here = format!("{:016x}", final_hash()); // any path: they agree

    let exe = std::env::current_exe().expect("test binary");
    let out = std::process::Command::new("qemu-x86_64")
        .args(["-cpu", "Nehalem"])
        .arg(exe)
        .args([
            "every_simd_path_gives_the_same_state_hash",
            "--exact",
            "--nocapture",
        ])
        .env("CRASH_EXPECT_HASH", &here)
        .env_remove("CRASH_SIMD")
        .output()
        .expect("qemu runs");
    let text = String::from_utf8_lossy(&out.stdout);
    println!("under qemu -cpu Nehalem:\n{text}");
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains(r#"paths on this CPU: ["baseline"]"#),
        "{text}"
    );
    assert!(
        text.contains(&format!("baseline: state hash {here}")),
        "{text}"
    );
}
