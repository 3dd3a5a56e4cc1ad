//! summary.json and the run-time error indicators.

mod common;

use common::test_dir;
use crash_core::EnergyTotals;
use crash_io::{hash_hex, read_summary, write_summary, Indicators, Summary};

fn e(
    kinetic: f64,
    internal: f64,
    hourglass: f64,
    contact: f64,
    balance_error: f64,
) -> EnergyTotals {
    EnergyTotals {
        kinetic,
        internal,
        hourglass,
        contact,
        balance_error,
        ..EnergyTotals::default()
    }
}

#[test]
fn indicators_track_peaks_and_ratios() {
    let mut ind = Indicators::default();
    ind.observe_energy(&e(10.0, 0.0, 0.0, 0.0, 0.0));
    ind.observe_energy(&e(2.0, 8.0, 0.4, 0.3, -0.004));
    ind.observe_energy(&e(9.0, 1.0, 0.1, 0.05, 0.002));
    ind.observe_penetration(0.2);
    ind.observe_penetration(0.1);
    assert_eq!(ind.final_balance_error, 0.002);
    assert_eq!(ind.peak_balance_error, 0.004);
    assert_eq!(ind.hourglass_internal_ratio, 0.4 / 8.0);
    assert_eq!(ind.contact_internal_ratio, 0.3 / 8.0);
    assert_eq!(ind.max_penetration_ratio, 0.2);
    assert!(ind.warnings().is_empty(), "{:?}", ind.warnings());

    ind.observe_energy(&e(1.0, 2.0, 1.2, -0.5, 0.03));
    let w = ind.warnings();
    assert_eq!(w.len(), 3, "{w:?}");
    assert!(w[0].contains("3.00%"), "{w:?}");
    assert!(w[1].contains("15.0%"), "hourglass 1.2 / 8: {w:?}");
    assert!(w[2].contains("negative"), "{w:?}");
    ind.observe_penetration(0.7);
    assert!(ind.warnings().iter().any(|s| s.contains("70%")));
}

#[test]
fn summary_json_round_trips_and_has_the_documented_fields() {
    let dir = test_dir("summary");
    let path = dir.join("summary.json");
    let mut ind = Indicators::default();
    ind.observe_energy(&e(1.0, 0.5, 0.01, 0.02, 1e-4));
    let s = Summary {
        scene: "sphere-on-plate".into(),
        scene_hash: hash_hex(0xdead_beef),
        bodies: 2,
        nodes: 1000,
        elements: 1800,
        steps: 12345,
        end_time: 2e-3,
        dt_min: 1.1e-7,
        dt_max: 1.3e-7,
        wall_time_s: 12.5,
        ns_per_element_cycle: [("elements".to_string(), 41.5), ("total".to_string(), 60.25)].into(),
        max_energy_balance_error: 1e-4,
        indicators: ind,
        warnings: ind.warnings(),
        final_state_hash: hash_hex(42),
        fault: None,
        simd_path: "avx2".into(),
    };
    write_summary(&path, &s).expect("write");
    assert_eq!(read_summary(&path).expect("read"), s);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("text")).expect("json");
    assert_eq!(v["final_state_hash"], "000000000000002a");
    assert_eq!(v["scene_hash"], "00000000deadbeef");
    assert_eq!(v["ns_per_element_cycle"]["total"], 60.25);
    assert_eq!(v["indicators"]["hourglass_internal_ratio"], 0.02);
    for k in [
        "scene",
        "bodies",
        "nodes",
        "elements",
        "steps",
        "end_time",
        "dt_min",
        "dt_max",
        "wall_time_s",
        "max_energy_balance_error",
        "warnings",
        "fault",
    ] {
        assert!(v.get(k).is_some(), "field {k}");
    }
}

#[test]
fn non_finite_numbers_are_written_as_null_and_read_back_as_nan() {
    let dir = test_dir("summary_null");
    let path = dir.join("summary.json");
    let s = Summary {
        dt_min: f64::INFINITY,
        fault: Some("step 3: non-finite velocity".into()),
        ..Summary::default()
    };
    write_summary(&path, &s).expect("write");
    let text = std::fs::read_to_string(&path).expect("text");
    assert!(text.contains("\"dt_min\": null"), "{text}");
    let back = read_summary(&path).expect("read");
    assert!(back.dt_min.is_nan());
    assert_eq!(back.dt_max, 0.0);
    assert_eq!(back.fault, s.fault);
}
