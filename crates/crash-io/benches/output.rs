//! Cost of writing and picturing one frame of a ~30k-element scene (a level-5 sphere,
//! 20480 triangles, over a 100 x 100 quad plate).

use crash_core::shapes::{icosphere, plate, ElementKind};
use crash_core::{Body, Material, Section, Stabilization, Vec3};
use crash_io::block_cache::BlockCache;
use crash_io::vtu::write_vtu;
use crash_io::vtu_encode::{FrameEncoder, Spill};
use crash_io::{render_frame, Colouring, Frame, Precision, RenderOptions, VtuFormat};
use criterion::{criterion_group, criterion_main, Criterion};

fn frame() -> Frame {
    let sec = |t| Section::new(Material::steel(), t);
    let p = Body::new(
        0,
        "plate",
        &plate(0.4, 0.4, 100, 100, ElementKind::Quad),
        sec(0.002),
        Stabilization::default(),
    )
    .expect("plate");
    let mut m = icosphere(0.1, 5);
    m.transform(&nalgebra::Matrix3::identity(), Vec3::new(0.0, 0.0, 0.12));
    let s = Body::new(1, "ball", &m, sec(0.001), Stabilization::default()).expect("ball");
    Frame::capture(0.0, 0, &[&p, &s])
}

fn bench(c: &mut Criterion) {
    let f = frame();
    let mut g = c.benchmark_group("frame_30k");
    g.sample_size(10);
    g.bench_function("capture", |b| {
        let p = Body::new(
            0,
            "plate",
            &plate(0.4, 0.4, 100, 100, ElementKind::Quad),
            Section::new(Material::steel(), 0.002),
            Stabilization::default(),
        )
        .expect("p");
        b.iter(|| Frame::capture(0.0, 0, &[&p]))
    });
    for (precision, compress, name) in [
        (Precision::F64, false, "f64_raw"),
        (Precision::F64, true, "f64_zlib"),
        (Precision::F32, true, "f32_zlib"),
    ] {
        let fmt = VtuFormat {
            precision,
            compress,
        };
        g.bench_function(format!("write_vtu_{name}"), |b| {
            let mut buf = Vec::with_capacity(1 << 24);
            b.iter(|| {
                buf.clear();
                write_vtu(&mut buf, &f, fmt).expect("write");
                buf.len()
            })
        });
        // a frame of a series: the bodies have moved since the last one (the moving
        // arrays are encoded again), their mesh and ids have not (the block cache)
        g.bench_function(format!("series_frame_{name}"), |b| {
            let mut buf = Vec::with_capacity(1 << 24);
            let mut cache = BlockCache::default();
            let mut moved = f.clone();
            b.iter(|| {
                for body in &mut moved.bodies {
                    for x in &mut body.x {
                        x.z += 1e-6;
                    }
                }
                buf.clear();
                let mut enc =
                    FrameEncoder::new(0.0, 0, fmt, Spill::in_memory(), std::mem::take(&mut cache));
                for body in &moved.bodies {
                    enc.body(body).expect("body");
                }
                cache = enc.finish(&mut buf).expect("write");
                buf.len()
            })
        });
    }
    g.bench_function("render_800x600_stress", |b| {
        let o = RenderOptions {
            colour: Colouring::ByVonMises { range: None },
            ..RenderOptions::default()
        };
        b.iter(|| render_frame(&f, &o))
    });
    g.bench_function("encode_png_800x600", |b| {
        let img = render_frame(&f, &RenderOptions::default());
        b.iter(|| img.encode_png().expect("png").len())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
