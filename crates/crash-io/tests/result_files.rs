//! The result files (matsum.csv & co.): body names with commas and quotes survive the
//! round trip through the matsum reader, and a reopen (restart, rollback) keeps the
//! complete rows up to its time, drops later and torn ones, and counts the columns of
//! quoted names right.
#![allow(clippy::unwrap_used)] // a test panics on failure

mod common;

use common::test_dir;
use crash_core::{BodyEnergy, Vec3};
use crash_io::matsum_read::{read_matsum_csv, MATSUM_HEADER};
use crash_io::{ResultFile, RCFORC_HEADER};
use std::io::Write;

fn energy(k: f64) -> BodyEnergy {
    BodyEnergy {
        kinetic: k,
        internal: 0.1 + 0.2,
        hourglass: 5e-324,
        contact: 7.0,
        damping: -0.0,
        external: 1.0,
    }
}

#[test]
fn quoted_names_round_trip_and_a_reopen_keeps_rows_up_to_its_time() {
    let dir = test_dir("result-files");
    let p = dir.join("matsum.csv");
    let names = ["plate", "left, upper", "the \"ball\""];
    let mut f = ResultFile::create(&p, MATSUM_HEADER).unwrap();
    for (step, t) in [(0u64, 0.0), (5, 1e-5), (10, 2e-5)] {
        for (k, n) in names.iter().enumerate() {
            f.matsum(step, t, n, &energy(k as f64 + t)).unwrap();
        }
    }
    f.flush().unwrap();
    drop(f);
    let rows = read_matsum_csv(&p).unwrap();
    assert_eq!(rows.len(), 9);
    let got: Vec<&str> = rows[..3].iter().map(|r| r.body.as_str()).collect();
    assert_eq!(got, names);
    assert_eq!(rows[4].internal.to_bits(), (0.1f64 + 0.2).to_bits());
    assert_eq!(rows[4].hourglass.to_bits(), 5e-324f64.to_bits());
    // a torn last line, then a reopen at 1e-5: steps 0 and 5 stay, 10 and the tear go
    std::fs::OpenOptions::new()
        .append(true)
        .open(&p)
        .unwrap()
        .write_all(b"15,3e-5,\"left, up")
        .unwrap();
    let mut f = ResultFile::reopen(&p, MATSUM_HEADER, 1e-5).unwrap();
    f.matsum(6, 1.5e-5, names[1], &energy(9.0)).unwrap();
    f.flush().unwrap();
    let rows = read_matsum_csv(&p).unwrap();
    let kept: Vec<(u64, &str)> = rows.iter().map(|r| (r.step, r.body.as_str())).collect();
    assert_eq!(
        kept,
        vec![
            (0, "plate"),
            (0, "left, upper"),
            (0, "the \"ball\""),
            (5, "plate"),
            (5, "left, upper"),
            (5, "the \"ball\""),
            (6, "left, upper"),
        ]
    );
}

#[test]
fn rcforc_rows_carry_the_force_vector_and_its_magnitude() {
    let dir = test_dir("result-rcforc");
    let p = dir.join("rcforc.csv");
    let mut f = ResultFile::create(&p, RCFORC_HEADER).unwrap();
    f.rcforc(3, 2.5e-6, "a", "b", Vec3::new(3.0, -4.0, 0.0))
        .unwrap();
    f.flush().unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    assert_eq!(
        text,
        format!("{RCFORC_HEADER}\n3,2.5e-6,a,b,3e0,-4e0,0e0,5e0\n")
    );
}
