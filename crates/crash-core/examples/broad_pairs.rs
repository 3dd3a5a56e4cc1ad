//! The body-pair search by testing every two boxes against the R-tree, per call (median
//! of 201), for body counts around `crash_core::contact::broad::DIRECT_MAX`: a floor
//! under spheres (one large box under a grid of small ones, each touching it) and a
//! sparse lattice (boxes 1.5 apart, no pairs).
//! Run: cargo run --release -p crash-core --example broad_pairs
use crash_core::contact::broad::{pairs_by_tree, pairs_direct, BodyBox};
use crash_core::Vec3;
use std::time::Instant;

fn floor(n: usize) -> Vec<BodyBox> {
    let side = (n as f64).sqrt().ceil() as usize;
    let mut b = vec![BodyBox {
        id: 0,
        lo: Vec3::new(0.0, 0.0, 0.0),
        hi: Vec3::new(side as f64, side as f64, 0.0),
        thickness: 0.01,
    }];
    for k in 1..n {
        let (i, j) = ((k - 1) % side, (k - 1) / side);
        let lo = Vec3::new(i as f64 + 0.1, j as f64 + 0.1, 0.02);
        b.push(BodyBox {
            id: k as u32,
            lo,
            hi: lo + Vec3::new(0.8, 0.8, 0.8),
            thickness: 0.01,
        });
    }
    b
}

fn lattice(n: usize) -> Vec<BodyBox> {
    let side = (n as f64).cbrt().ceil() as usize;
    (0..n)
        .map(|k| {
            let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
            let lo = Vec3::new(1.5 * i as f64, 1.5 * j as f64, 1.5 * l as f64);
            BodyBox {
                id: k as u32,
                lo,
                hi: lo + Vec3::new(1.0, 1.0, 1.0),
                thickness: 0.01,
            }
        })
        .collect()
}

fn median_ns(mut f: impl FnMut() -> usize) -> (f64, usize) {
    let mut t = Vec::new();
    let mut found = 0;
    for _ in 0..201 {
        let s = Instant::now();
        found = std::hint::black_box(f());
        t.push(s.elapsed().as_nanos() as f64);
    }
    t.sort_by(f64::total_cmp);
    (t[t.len() / 2], found)
}

fn main() {
    println!("| layout | bodies | pairs | every two [us] | R-tree [us] |");
    println!("| --- | --- | --- | --- | --- |");
    for (name, make) in [
        ("floor", floor as fn(usize) -> Vec<BodyBox>),
        ("lattice", lattice),
    ] {
        for n in [16, 65, 128, 256, 512, 1024, 2048] {
            let boxes = make(n);
            let (d, pd) = median_ns(|| pairs_direct(&boxes, 0.02).len());
            let (t, pt) = median_ns(|| pairs_by_tree(&boxes, 0.02).len());
            assert_eq!(pd, pt);
            println!("| {name} | {n} | {pd} | {:.1} | {:.1} |", d / 1e3, t / 1e3);
        }
    }
}
