//! summary.json and the run-time error indicators.

mod common;

use common::test_dir;
use crash_core::EnergyTotals;
use crash_io::{hash_hex, read_summary, write_summary, Indicators, Summary, Warning, WarningKind};

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

fn run_e(e: EnergyTotals, run_error: f64) -> EnergyTotals {
    EnergyTotals { run_error, ..e }
}

#[test]
fn indicators_judge_the_energy_balance_against_the_scene_limit_alone() {
    // one limit: 5 % (the scene's), not a fixed 1 %
    let mut ind = Indicators::new(0.05);
    ind.observe_energy(&run_e(e(10.0, 0.0, 0.0, 0.0, 0.0), 0.0));
    ind.observe_energy(&run_e(e(2.0, 8.0, 0.4, 0.3, -0.04), 0.04));
    assert_eq!(ind.energy_balance_error, 0.04);
    assert!(ind.exceeded().is_empty(), "{:?}", ind.exceeded());
    ind.observe_energy(&run_e(e(2.0, 8.0, 0.4, 0.3, -0.06), 0.06));
    let w = ind.exceeded();
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].0, WarningKind::EnergyBalance);
    assert!(
        w[0].1.contains("6.000%") && w[0].1.contains("5.000%"),
        "{w:?}"
    );
}

#[test]
fn indicators_track_hourglass_ratio_and_penetration() {
    let mut ind = Indicators::new(0.05);
    ind.observe_energy(&e(2.0, 8.0, 0.4, 0.0, 0.0));
    ind.observe_penetration(0.2);
    ind.observe_penetration(0.1);
    assert_eq!(ind.hourglass_internal_ratio, 0.4 / 8.0);
    assert_eq!(ind.max_penetration_ratio, 0.2);
    assert!(ind.exceeded().is_empty());
    ind.observe_energy(&e(1.0, 2.0, 1.2, 0.0, 0.0));
    let w = ind.exceeded();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].1.contains("15.0%"), "hourglass 1.2 / 8: {w:?}");
}

#[test]
fn stored_contact_energy_is_benign_and_made_contact_energy_is_judged_against_the_flow() {
    // a stiff bounce of a heavy body on a light one: the contact stores far more than
    // the bodies' internal energy (the old "contact energy 12.5% of internal" case),
    // then gives it back
    let mut ind = Indicators::new(0.05);
    for c in [0.0, 0.5, 1.0, 0.5, 0.0, -0.02] {
        ind.observe_energy(&e(10.0 - c, 0.01, 0.0, c, 0.0));
    }
    assert_eq!(ind.contact_flow_j, 1.0);
    assert_eq!(ind.min_contact_energy_j, -0.02);
    assert!((ind.contact_generated_ratio - 0.02).abs() < 1e-15);
    assert!(ind.exceeded().is_empty(), "{:?}", ind.exceeded());
    // contact that makes 15 % of what flowed through it is not benign
    ind.observe_energy(&e(10.15, 0.01, 0.0, -0.15, 0.0));
    let w = ind.exceeded();
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].0, WarningKind::ContactEnergy);
    assert!(w[0].1.contains("15.0%"), "{w:?}");
}

#[test]
fn summary_json_round_trips_and_has_the_documented_fields() {
    let dir = test_dir("summary");
    let path = dir.join("summary.json");
    let mut ind = Indicators::default();
    ind.observe_energy(&e(1.0, 0.5, 0.01, 0.02, 1e-4));
    let warning = Warning {
        kind: WarningKind::Penetration,
        step: 12,
        time_s: 1.5e-6,
        bodies: vec!["plate".into(), "sphere".into()],
        message: "penetration reached 70% of the thinner shell's thickness (limit 50%)".into(),
        doubtful: true,
    };
    let s = Summary {
        scene: "sphere-on-plate".into(),
        scene_hash: hash_hex(0xdead_beef),
        bodies: 2,
        nodes: 1000,
        elements: 1800,
        steps: 12345,
        time_reached_s: 2e-3,
        dt_min_s: 1.1e-7,
        dt_max_s: 1.3e-7,
        last_dt_s: 2e-8,
        wall_time_s: 12.5,
        ns_per_element_cycle: [("elements".to_string(), 41.5), ("total".to_string(), 60.25)].into(),
        barrier_us_per_step: [("median".to_string(), 31.5)].into(),
        energy_balance_error: 1e-4,
        energy_limit: 0.05,
        indicators: ind,
        warnings: vec![warning],
        final_state_hash: hash_hex(42),
        fault: None,
        interrupted: false,
        simd_path: "avx2".into(),
        cluster: crash_io::summary::ClusterSummary {
            workers: 2,
            migrations: 3,
            group_changes: 4,
            splits_kept: 1,
            splits: 2,
            halo_direct_steps: 5,
            halo_relayed_steps: 6,
            max_groups: 13,
            final_groups: vec![crash_io::summary::GroupSummary {
                group: 0,
                bodies: vec![0],
                worker: 1,
            }],
            compute_ns_per_worker: vec![10, 12],
        },
    };
    write_summary(&path, &s).expect("write");
    assert_eq!(read_summary(&path).expect("read"), s);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("text")).expect("json");
    assert_eq!(v["final_state_hash"], "000000000000002a");
    assert_eq!(v["scene_hash"], "00000000deadbeef");
    assert_eq!(v["ns_per_element_cycle"]["total"], 60.25);
    assert_eq!(v["interrupted"], false);
    // a summary.json written before `interrupted` existed still reads (as false)
    let mut old = v.clone();
    old.as_object_mut().expect("object").remove("interrupted");
    std::fs::write(&path, old.to_string()).expect("write old");
    assert_eq!(read_summary(&path).expect("read old"), s);
    assert_eq!(v["indicators"]["hourglass_internal_ratio"], 0.02);
    assert_eq!(v["warnings"][0]["kind"], "penetration");
    assert_eq!(v["warnings"][0]["step"], 12);
    assert_eq!(v["warnings"][0]["bodies"][1], "sphere");
    // every number's field name carries its unit, or it is a count or a ratio
    for k in [
        "scene",
        "bodies",
        "nodes",
        "elements",
        "steps",
        "time_reached_s",
        "dt_min_s",
        "dt_max_s",
        "last_dt_s",
        "wall_time_s",
        "energy_balance_error",
        "energy_limit",
        "warnings",
        "fault",
    ] {
        assert!(v.get(k).is_some(), "field {k}");
    }
    for k in ["peak_internal_j", "contact_flow_j", "min_contact_energy_j"] {
        assert!(v["indicators"].get(k).is_some(), "indicators.{k}");
    }
}

#[test]
fn non_finite_numbers_are_written_as_null_and_read_back_as_nan() {
    let dir = test_dir("summary_null");
    let path = dir.join("summary.json");
    let s = Summary {
        dt_min_s: f64::INFINITY,
        fault: Some("step 3: non-finite velocity".into()),
        ..Summary::default()
    };
    write_summary(&path, &s).expect("write");
    let text = std::fs::read_to_string(&path).expect("text");
    assert!(text.contains("\"dt_min_s\": null"), "{text}");
    let back = read_summary(&path).expect("read");
    assert!(back.dt_min_s.is_nan());
    assert_eq!(back.dt_max_s, 0.0);
    assert_eq!(back.fault, s.fault);
}
