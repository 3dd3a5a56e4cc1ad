//! Contact cost. Run: `cargo bench -p crash-core --bench contact`.
//!
//! 1. `stage/*`: one contact pass (level i, Verlet check, level ii, penalty forces,
//!    gather) on a scene held in contact, trees warm. Throughput = nodes of the contact
//!    bodies, so ns per contact node per cycle = time per iteration / nodes.
//!    - `plate_stack`: 5 plates of 40 x 40 quads (1681 nodes each) stacked 1% of their
//!      thickness inside each other: every node is in contact (worst case).
//!    - `ten_spheres_three_plates`: 10 icospheres (level 3, 642 nodes) resting on 3
//!      plates of 30 x 30 quads, 1% of the thickness pressed in.
//! 2. `search/*`: level ii alone, 1089 nodes of a plate lying on a triangulated plate of
//!    about 1k, 10k or 100k segments: R-tree query + closest-point projection against
//!    every segment (brute force). Brute force uses fewer query nodes at 10k and 100k
//!    (shown in the name); throughput is per query node in both, so ns per node compare
//!    directly. `build/*` is one bulk load of the segment tree.

use crash_core::contact::narrow::search;
use crash_core::contact::surface::{node_chunks, Surface};
use crash_core::contact::verlet::NodeLists;
use crash_core::contact::{
    body_bounds, contact_forces, project, segments, ContactConfig, ContactState,
};
use crash_core::shapes::{icosphere, plate, ElementKind};
use crash_core::{dof, Body, Material, Section, Stabilization, Vec3};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use std::time::Duration;

const T: f64 = 0.002;

fn body(id: u32, mesh: &crash_core::Mesh, at: Vec3) -> Body {
    let mat = Material::steel();
    let mut m = mesh.clone();
    m.transform(&nalgebra::Matrix3::identity(), at);
    let mut b =
        Body::new(id, "b", &m, Section::new(mat, T), Stabilization::default()).expect("valid");
    b.def_mut().contact = true;
    b
}

fn plate_stack() -> Vec<Body> {
    let m = plate(0.4, 0.4, 40, 40, ElementKind::Quad);
    (0..5)
        .map(|k| body(k, &m, Vec3::new(0.0, 0.0, k as f64 * 0.99 * T)))
        .collect()
}

fn spheres_on_plates() -> Vec<Body> {
    let (r, lp) = (0.05, 0.4);
    let pm = plate(lp, lp, 30, 30, ElementKind::Quad);
    let sm = icosphere(r, 3);
    let mut out = Vec::new();
    for p in 0..3u32 {
        let origin = Vec3::new(p as f64 * 0.5, 0.0, 0.0);
        let mut pl = body(p, &pm, origin);
        for i in 0..pl.state.x.len() {
            pl.fix(i, dof::ALL);
        }
        out.push(pl);
    }
    // 4 + 3 + 3 spheres on the three plates, poles pressed 1% of t into the plate
    let mut id = 3;
    for (p, n) in [(0, 4), (1, 3), (2, 3)] {
        for s in 0..n {
            let x = p as f64 * 0.5 + (s as f64 - 1.5) * 0.11;
            let c = Vec3::new(x, 0.0, r + 0.99 * T);
            out.push(body(id, &sm, c));
            id += 1;
        }
    }
    out
}

fn stage_bench(c: &mut Criterion, name: &str, mut bodies: Vec<Body>) {
    let cfg = ContactConfig {
        margin: 1e-3,
        ..Default::default()
    };
    let dts: Vec<f64> = bodies.iter().map(|_| 1e-6).collect();
    let boxes = body_bounds(&bodies);
    let mut state = ContactState::default();
    contact_forces(&mut bodies, &cfg, &mut state, &dts, &boxes, 0.0, 0)
        .expect("no crossing check at h = 0");
    let nodes: usize = bodies.iter().map(|b| b.state.x.len()).sum();
    let active: usize = state.stats().iter().map(|s| s.active_nodes).sum();
    println!(
        "{name}: {} bodies, {nodes} contact-body nodes, {active} active contacts, {} pairs",
        bodies.len(),
        state.stats().len()
    );
    let mut g = c.benchmark_group("stage");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_secs(1));
    g.throughput(Throughput::Elements(nodes as u64));
    g.bench_function(name, |b| {
        b.iter(|| {
            black_box(contact_forces(
                &mut bodies,
                &cfg,
                &mut state,
                &dts,
                &boxes,
                0.0,
                0,
            ))
        })
    });
    g.finish();
}

fn search_bench(c: &mut Criterion) {
    let q = body(
        1,
        &plate(0.9, 0.9, 32, 32, ElementKind::Quad),
        Vec3::new(0.0, 0.0, 0.6 * T),
    );
    for (label, n, brute_nodes) in [
        ("1k", 22usize, 1089usize),
        ("10k", 71, 100),
        ("100k", 224, 10),
    ] {
        let s = body(0, &plate(1.0, 1.0, n, n, ElementKind::Tri), Vec3::zeros());
        let segs = segments(&s);
        let mut surf = Surface::new(&s);
        surf.refresh(&s, 1e-3);
        // fresh node lists each time: every node walks the tree (the path measured)
        let pass = || {
            search(
                &q,
                &node_chunks(&q),
                &s,
                &surf,
                false,
                &mut NodeLists::default(),
            )
        };
        let hits = pass().len();
        println!(
            "{label}: {} segments, {} query nodes, {hits} hits",
            segs.len(),
            q.state.x.len()
        );
        let mut g = c.benchmark_group(format!("search/{label}"));
        g.sample_size(10)
            .measurement_time(Duration::from_secs(2))
            .warm_up_time(Duration::from_millis(500));
        g.throughput(Throughput::Elements(q.state.x.len() as u64));
        g.bench_function("rtree", |b| b.iter(|| black_box(pass())));
        g.throughput(Throughput::Elements(brute_nodes as u64));
        g.bench_function(format!("brute_{brute_nodes}_nodes"), |b| {
            b.iter(|| {
                let mut found = 0usize;
                for p in &q.state.x[..brute_nodes] {
                    let mut best = f64::INFINITY;
                    for seg in &segs {
                        best = best.min(project(p, seg, &s.state.x).dist);
                    }
                    found += usize::from(best < T);
                }
                black_box(found)
            })
        });
        g.throughput(Throughput::Elements(segs.len() as u64));
        g.bench_function("build", |b| {
            b.iter(|| {
                let mut fresh = Surface::new(&s);
                black_box(fresh.refresh(&s, 1e-3))
            })
        });
        g.finish();
    }
}

fn bench(c: &mut Criterion) {
    // one thread: the numbers are per core (build_global fails only if already set)
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global();
    stage_bench(c, "plate_stack", plate_stack());
    stage_bench(c, "ten_spheres_three_plates", spheres_on_plates());
    search_bench(c);
}

criterion_group!(benches, bench);
criterion_main!(benches);
