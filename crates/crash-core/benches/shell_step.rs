//! Time per element-cycle of the shell pipeline on a 100 000-element plate:
//! element internal forces alone, and the whole step (forces + gather + integration),
//! at 1 and 2 threads. Run: `cargo bench -p crash-core --bench shell_step`.
//! Criterion reports time per iteration = one cycle of 100 000 elements, so
//! ns per element-cycle = reported time / 1e5 (also shown as throughput).

use crash_core::shapes::{bench_plate, ElementKind};
use crash_core::{Body, Group, Vec3};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::time::Duration;

fn plate_body(kind: ElementKind) -> Body {
    match kind {
        ElementKind::Tri => bench_plate(224, 224, kind), // 100 352 triangles
        ElementKind::Quad => bench_plate(317, 316, kind), // 100 172 quads
    }
}

fn bench(c: &mut Criterion) {
    for kind in [ElementKind::Tri, ElementKind::Quad] {
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let body = plate_body(kind);
            let n = body.element_count() as u64;
            let mut g = c.benchmark_group(format!("{kind:?}/{threads}t"));
            g.sample_size(10)
                .measurement_time(Duration::from_secs(4))
                .warm_up_time(Duration::from_secs(1));
            g.throughput(Throughput::Elements(n));
            let mut b = body.clone();
            g.bench_function("internal_forces", |bch| {
                pool.install(|| bch.iter(|| b.internal_forces(1e-7, 1).expect("forces")))
            });
            let mut group = Group::new(vec![body.clone()], Vec3::zeros());
            pool.install(|| group.start().expect("start"));
            let mut clock = crash_core::Clock::default();
            g.bench_function("whole_step", |bch| {
                pool.install(|| {
                    bch.iter(|| {
                        let r = group.advance(&clock, 1e-7).expect("step");
                        clock = clock.after(1e-7);
                        r
                    })
                })
            });
            g.finish();
        }
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
