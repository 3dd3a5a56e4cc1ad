//! Each raw array file named on the command line compressed in 64 KiB blocks (as
//! crash-io writes them) at zlib-rs levels 1 and 2: its compressed size over its raw
//! size and the time, mean of five repetitions.
use zlib_rs::{compress_slice, compress_bound, DeflateConfig};
use std::time::Instant;
fn main() {
    let mut out = vec![0u8; compress_bound(1 << 16)];
    for path in std::env::args().skip(1) {
        let raw = std::fs::read(&path).unwrap();
        let name = std::path::Path::new(&path)
            .file_name()
            .map_or(path.clone(), |n| n.to_string_lossy().into_owned());
        let mut line = format!("{name:28} {:8}", raw.len());
        for level in [1, 2] {
            let cfg = DeflateConfig::new(level);
            let reps = 5;
            let t = Instant::now();
            let mut total = 0usize;
            for _ in 0..reps {
                total = 0;
                for blk in raw.chunks(1 << 16) {
                    let (o, _) = compress_slice(&mut out, blk, cfg);
                    total += o.len();
                }
            }
            let dt = t.elapsed().as_secs_f64() / reps as f64;
            line += &format!(" | l{level}: {:.3} {:.2} ms", total as f64 / raw.len() as f64, dt * 1e3);
        }
        println!("{line}");
    }
}
