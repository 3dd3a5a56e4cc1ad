//! CSV histories: exact round trip of every f64, restart truncation, torn lines.

mod common;

use common::test_dir;
use crash_core::EnergyTotals;
use crash_io::{read_contacts_csv, read_energy_csv, ContactHistory, ContactRow, EnergyHistory};

/// Deterministic pseudo-random f64 bit patterns (xorshift), finite ones only.
fn tricky_values(n: usize) -> Vec<f64> {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut out = vec![
        0.0,
        -0.0,
        f64::MIN_POSITIVE,
        f64::MIN_POSITIVE / 3.0, // subnormal
        f64::MAX,
        -f64::MAX,
        f64::EPSILON,
        0.1 + 0.2,
        1.0 / 3.0,
        5e-324,
    ];
    while out.len() < n {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        let v = f64::from_bits(s);
        if v.is_finite() {
            out.push(v);
        }
    }
    out
}

fn totals(v: &[f64]) -> EnergyTotals {
    EnergyTotals {
        kinetic: v[0],
        internal: v[1],
        hourglass: v[2],
        contact: v[3],
        damping: v[4],
        external: v[5],
        balance_error: v[6],
        run_error: 0.0,
    }
}

#[test]
fn energy_csv_round_trips_every_bit() {
    let dir = test_dir("energy_round_trip");
    let path = dir.join("energy.csv");
    let vals = tricky_values(8 * 500);
    let mut h = EnergyHistory::create(&path).expect("create");
    for row in vals.chunks_exact(8) {
        h.write(row[0], &totals(&row[1..])).expect("write");
    }
    h.flush().expect("flush");
    let back = read_energy_csv(&path).expect("read");
    assert_eq!(back.len(), 500);
    for (r, v) in back.iter().zip(vals.chunks_exact(8)) {
        let e = &r.energy;
        let got = [
            r.time,
            e.kinetic,
            e.internal,
            e.hourglass,
            e.contact,
            e.damping,
            e.external,
            e.balance_error,
        ];
        for (a, b) in got.iter().zip(v) {
            assert_eq!(a.to_bits(), b.to_bits(), "{a:e} vs {b:e}");
        }
    }
    let text = std::fs::read_to_string(&path).expect("text");
    assert_eq!(
        text.lines().next(),
        Some("time,kinetic,internal,hourglass,contact,damping,external_work,balance_error")
    );
}

#[test]
fn contacts_csv_round_trips_and_has_its_header() {
    let dir = test_dir("contacts_round_trip");
    let path = dir.join("contacts.csv");
    let mut h = ContactHistory::create(&path).expect("create");
    let rows: Vec<ContactRow> = tricky_values(300)
        .chunks_exact(3)
        .enumerate()
        .map(|(k, v)| ContactRow {
            time: v[0],
            a: k as u32,
            b: 4_000_000_000 - k as u32,
            force: v[1],
            penetration: v[2],
        })
        .collect();
    rows.iter().for_each(|r| h.write(r).expect("write"));
    h.flush().expect("flush");
    let back = read_contacts_csv(&path).expect("read");
    assert_eq!(back.len(), rows.len());
    for (a, b) in back.iter().zip(&rows) {
        assert_eq!((a.a, a.b), (b.a, b.b));
        assert_eq!(
            [a.time.to_bits(), a.force.to_bits(), a.penetration.to_bits()],
            [b.time.to_bits(), b.force.to_bits(), b.penetration.to_bits()]
        );
    }
    let text = std::fs::read_to_string(&path).expect("text");
    assert_eq!(
        text.lines().next(),
        Some("time,body_a,body_b,normal_force,max_penetration")
    );
}

#[test]
fn reopen_drops_rows_after_the_restart_time_and_appends() {
    let dir = test_dir("energy_reopen");
    let path = dir.join("energy.csv");
    let e = totals(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
    {
        let mut h = EnergyHistory::create(&path).expect("create");
        for k in 0..10 {
            h.write(k as f64 * 0.5, &e).expect("write");
        }
    }
    // An interrupted write leaves a torn last line.
    let mut text = std::fs::read_to_string(&path).expect("text");
    text.push_str("5e0,1e0,2e");
    std::fs::write(&path, &text).expect("tear");
    let full_prefix: String = text.lines().take(1 + 7).map(|l| format!("{l}\n")).collect();

    let mut h = EnergyHistory::reopen(&path, 3.0).expect("reopen");
    h.write(3.25, &e).expect("write");
    h.flush().expect("flush");
    let back = read_energy_csv(&path).expect("read");
    let times: Vec<f64> = back.iter().map(|r| r.time).collect();
    assert_eq!(times, vec![0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.25]);
    // The kept rows are byte-identical to the ones written before the restart.
    let now = std::fs::read_to_string(&path).expect("text");
    assert!(now.starts_with(&full_prefix));
}

#[test]
fn reopen_keeps_rows_up_to_a_torn_line_and_drops_the_rest() {
    let dir = test_dir("contacts_torn");
    let path = dir.join("contacts.csv");
    std::fs::write(
        &path,
        "time,body_a,body_b,normal_force,max_penetration\n1e0,0,1,2e0,1e-4\n2e0,0,1\n3e0,0,1,2e0,1e-4\n",
    )
    .expect("write");
    let h = ContactHistory::reopen(&path, 10.0).expect("reopen");
    drop(h);
    assert_eq!(read_contacts_csv(&path).expect("read").len(), 1);
}

#[test]
fn reading_a_bad_csv_names_the_file_and_line() {
    let dir = test_dir("energy_bad");
    let path = dir.join("energy.csv");
    std::fs::write(
        &path,
        "time,kinetic,internal,hourglass,contact,damping,external_work,balance_error\n0,1,2,3,4,5,6,x\n",
    )
    .expect("write");
    let err = read_energy_csv(&path).expect_err("bad number").to_string();
    assert!(
        err.contains("energy.csv") && err.contains("line 2"),
        "{err}"
    );
    std::fs::write(&path, "t,k\n").expect("write");
    let err = EnergyHistory::reopen(&path, 1.0)
        .expect_err("bad header")
        .to_string();
    assert!(
        err.contains("energy.csv") && err.contains("header"),
        "{err}"
    );
}
