//! MEIM update and grouping per step: level-i search over all body boxes, edge update,
//! connected components. Bodies sit on a cubic lattice; every fifth body touches its
//! +x neighbour (a few hundred edges at 1 000 bodies). "steady": the same boxes every
//! step (no group change, the common case); "changing": every step alternately adds and
//! removes a touching pair (groups recomputed each step); "drifting": every box moves
//! 1/40 of the skin per step (the cached list is rebuilt by a full search every ~18
//! steps); "full_search": the full level-i search alone (the rebuild).
#![allow(clippy::unwrap_used)]

use crash_core::contact::candidate_pairs;
use crash_core::contact::BodyBox;
use crash_core::Vec3;
use crash_master::meim::Meim;
use crash_master::pairs::PairSearch;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

fn lattice(n: usize) -> Vec<BodyBox> {
    let side = (n as f64).cbrt().ceil() as usize;
    (0..n)
        .map(|i| {
            let (x, y, z) = (i % side, (i / side) % side, i / (side * side));
            // boxes of 0.8 at spacing 1.0; every fifth stretched to reach its neighbour
            let lo = Vec3::new(x as f64, y as f64, z as f64);
            let len = if i % 5 == 0 { 1.05 } else { 0.8 };
            BodyBox {
                id: i as u32,
                lo,
                hi: lo + Vec3::new(len, 0.8, 0.8),
                thickness: 0.01,
            }
        })
        .collect()
}

fn meim(c: &mut Criterion) {
    let mut g = c.benchmark_group("meim_update");
    for n in [10usize, 1_000, 10_000] {
        let boxes = lattice(n);
        let ids: Vec<u32> = boxes.iter().map(|b| b.id).collect();
        let mut m = Meim::new(&ids, 0);
        let mut s = PairSearch::new(0.02, 0.1);
        let mut step = 0;
        g.bench_with_input(BenchmarkId::new("steady", n), &n, |b, _| {
            b.iter(|| {
                step += 1;
                let pairs = s.pairs(&boxes);
                m.update(step, &pairs)
            })
        });
        let mut moving = boxes.clone();
        let mut m = Meim::new(&ids, 0);
        let mut s = PairSearch::new(0.02, 0.1);
        g.bench_with_input(BenchmarkId::new("changing", n), &n, |b, _| {
            b.iter(|| {
                step += 1;
                moving[1].hi.x = if step % 2 == 0 { 2.05 } else { 1.8 };
                let pairs = s.pairs(&moving);
                m.update(step, &pairs)
            })
        });
        let mut drift = boxes.clone();
        let mut m = Meim::new(&ids, 0);
        let mut s = PairSearch::new(0.02, 0.1);
        g.bench_with_input(BenchmarkId::new("drifting", n), &n, |b, _| {
            b.iter(|| {
                step += 1;
                let d = Vec3::new(0.0025, 0.0, 0.0);
                for bx in &mut drift {
                    bx.lo += d;
                    bx.hi += d;
                }
                let pairs = s.pairs(&drift);
                m.update(step, &pairs)
            })
        });
        g.bench_with_input(BenchmarkId::new("full_search", n), &n, |b, _| {
            b.iter(|| candidate_pairs(&boxes, 0.02))
        });
    }
    g.finish();
}

criterion_group!(benches, meim);
criterion_main!(benches);
