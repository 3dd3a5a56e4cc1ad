//! Fast motion: no node passes through a contact surface silently (docs/theory-contact.md,
//! "Fast motion"). A thin sphere (R/t = 200) thrown at 2000 m/s onto a clamped plate
//! passed straight through it before the crossing check existed.

mod contact_util;

use contact_util::*;
use crash_core::contact::{ContactConfig, SpeedRule, CLOSING_FRACTION};
use crash_core::{Fault, Run, RunConfig, Vec3};

const R: f64 = 0.05;
const T_SPHERE: f64 = 2.5e-4; // R/t = 200
const T_PLATE: f64 = 1e-3;

fn thrown(speed: f64, rule: SpeedRule) -> Run {
    let z = R + 0.5 * (T_SPHERE + T_PLATE) + 1e-3;
    let s = sphere(
        0,
        R,
        T_SPHERE,
        3,
        Vec3::new(0.0, 0.0, z),
        Vec3::new(0.0, 0.0, -speed),
    );
    let p = fixed_plate(1, 0.2, 20, T_PLATE, 0.0);
    let cfg = ContactConfig {
        margin: (2e-5 * speed).max(2e-3),
        speed_rule: rule,
        ..Default::default()
    };
    Run::new(
        group(vec![s, p], cfg),
        RunConfig {
            // long enough to cross the whole sphere at that speed
            end_time: 3.0 * R / speed,
            ..Default::default()
        },
    )
    .expect("starts")
}

/// Lowest sphere node over the plate's footprint, relative to the plate's mid-surface.
fn lowest_over_plate(run: &Run) -> f64 {
    run.group.bodies[0]
        .state
        .x
        .iter()
        .filter(|x| x.x.abs() < 0.1 && x.y.abs() < 0.1)
        .map(|x| x.z)
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn crossing_at_2000_m_s_stops_the_run_naming_both_bodies_under_the_stop_rule() {
    let mut run = thrown(2000.0, SpeedRule::Stop);
    let err = run
        .run(|_| {})
        .expect_err("a pass-through must stop the run");
    println!("{err}");
    match &err {
        Fault::PassThrough {
            body_name,
            other_name,
            closing_speed,
            step,
            ..
        } => {
            let names = [body_name.as_str(), other_name.as_str()];
            assert!(names.contains(&"b0") && names.contains(&"b1"), "{names:?}");
            // the node and the crossed point close at about the impact speed
            assert!(
                *closing_speed > 1000.0 && *closing_speed < 2500.0,
                "{closing_speed}"
            );
            assert!(*step >= 1);
        }
        other => panic!("expected a pass-through, got {other}"),
    }
    // stopped at the crossing step: no node is more than one step's travel below
    let travel = 2000.0 * run.dt_max;
    assert!(lowest_over_plate(&run) > -travel - T_PLATE);
}

#[test]
fn limit_dt_rule_keeps_every_node_on_its_side_at_2000_m_s_or_stops_named() {
    let mut run = thrown(2000.0, SpeedRule::LimitDt);
    let mut limited = false;
    let c = 0.5 * (T_SPHERE + T_PLATE);
    let result = run.run(|r| {
        // once the pair is a candidate the step is at most safety * f c / v_close
        if r.group.contact_stats().iter().any(|s| s.a == 0 && s.b == 1) {
            limited |= r.next_dt <= 0.9 * CLOSING_FRACTION * c / 1900.0;
        }
    });
    match result {
        Ok(()) => {
            let low = lowest_over_plate(&run);
            println!("finished, lowest sphere node over the plate z = {low:.3e} m");
            assert!(low > 0.0, "a node is below the plate's mid-surface: {low}");
            let v = com_velocity(&run.group.bodies[0]);
            println!("sphere velocity after {v:?}");
        }
        Err(e) => {
            println!("stopped: {e}");
            assert!(!matches!(e, Fault::Tunnelling { .. }), "{e}");
        }
    }
    assert!(limited, "the closing speed never limited the step");
}

#[test]
fn closing_speed_limit_changes_nothing_at_2_m_s() {
    let energies = |rule| {
        let mut run = thrown(2.0, rule);
        run.cfg.end_time = 2e-3;
        let mut e = Vec::new();
        run.run(|r| e.push(r.energy.total().to_bits()))
            .expect("runs");
        (e, run.dt_min)
    };
    let (a, dta) = energies(SpeedRule::LimitDt);
    let (b, dtb) = energies(SpeedRule::Stop);
    assert_eq!(dta, dtb);
    assert_eq!(a, b);
}
