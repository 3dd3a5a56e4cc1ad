//! The platform's floor under the barrier: a blocking TCP ping-pong between two
//! processes on loopback (no tonic, no HTTP/2, no async runtime), 8-byte messages,
//! TCP_NODELAY. The round trip is two wake-ups of a sleeping process, which is what one
//! exchange of a step costs at the least (master -> worker -> master).
//!
//! Run: cargo run --release -p crash-tests --example loopback_pingpong [-- ROUND_TRIPS]
//! (default 10 000, after 1 000 unmeasured). Prints the median, the 10th and 90th
//! percentiles and the mean in microseconds.
#![allow(clippy::unwrap_used)]

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::process::Command;
use std::time::Instant;

const WARM_UP: usize = 1_000;

/// The child: connect to the parent and echo every message back.
fn echo(addr: &str) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_nodelay(true).unwrap();
    let mut buf = [0u8; 8];
    while s.read_exact(&mut buf).is_ok() {
        if s.write_all(&buf).is_err() {
            break;
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--echo") {
        echo(&args[1]);
        return;
    }
    let n: usize = args.iter().find_map(|a| a.parse().ok()).unwrap_or(10_000);
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args(["--echo", &addr])
        .spawn()
        .unwrap();
    let (mut s, _) = listener.accept().unwrap();
    s.set_nodelay(true).unwrap();
    let mut buf = [0u8; 8];
    let mut us = Vec::with_capacity(n);
    for k in 0..WARM_UP + n {
        let t = Instant::now();
        s.write_all(&(k as u64).to_le_bytes()).unwrap();
        s.read_exact(&mut buf).unwrap();
        if k >= WARM_UP {
            us.push(t.elapsed().as_secs_f64() * 1e6);
        }
    }
    drop(s);
    let _ = child.wait();
    let mean = us.iter().sum::<f64>() / n as f64;
    us.sort_by(f64::total_cmp);
    let q = |f: f64| us[((n - 1) as f64 * f) as usize];
    println!(
        "loopback TCP ping-pong between two processes, {n} round trips: median {:.1} us (p10 {:.1}, p90 {:.1}, mean {mean:.1})",
        q(0.5),
        q(0.1),
        q(0.9)
    );
}
