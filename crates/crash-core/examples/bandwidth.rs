//! What two threads of this machine get from memory together against one: a
//! read-modify-write stream over 4, 64 and 256 MB per thread (16 bytes moved per
//! element). Element and node loops that miss the cache cannot scale beyond this ratio.
//! `cargo run --release -p crash-core --example bandwidth`

use std::time::Instant;

fn stream(v: &mut [f64], reps: usize) -> f64 {
    let t = Instant::now();
    for _ in 0..reps {
        for x in v.iter_mut() {
            *x = *x * 1.000_000_1 + 0.5;
        }
    }
    std::hint::black_box(&v);
    (v.len() * 16 * reps) as f64 / t.elapsed().as_secs_f64() / 1e9
}

fn main() {
    println!("| MB per thread | 1 thread [GB/s] | 2 threads together [GB/s] | ratio |");
    println!("| --- | --- | --- | --- |");
    for mb in [4usize, 64, 256] {
        let n = mb * 1024 * 1024 / 8;
        let reps = (512 / mb).max(2);
        let mut a = vec![1.0f64; n];
        let mut b = vec![1.0f64; n];
        stream(&mut a, 1);
        let one = stream(&mut a, reps);
        let (x, y) = std::thread::scope(|s| {
            let h1 = s.spawn(|| stream(&mut a, reps));
            let h2 = s.spawn(|| stream(&mut b, reps));
            (h1.join().unwrap_or(f64::NAN), h2.join().unwrap_or(f64::NAN))
        });
        println!("| {mb} | {one:.1} | {:.1} | {:.2}x |", x + y, (x + y) / one);
    }
}
