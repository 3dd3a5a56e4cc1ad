//! The quick slice of the stability matrix (`crash study stability --quick`): no cell
//! blows up silently, every cell meets its expected outcome, and the guards answer each
//! extreme with the diagnostic that names its cause.

use crash_cli::study::matrix::{run_matrix, CellResult};
use crash_cli::study::outcome::{Outcome, Stage};

fn find<'a>(res: &'a [CellResult], axis: &str, value: &str) -> &'a Outcome {
    &res.iter()
        .find(|r| r.cell.axis.starts_with(axis) && r.cell.value == value)
        .unwrap_or_else(|| panic!("cell {axis} = {value} in the quick slice"))
        .outcome
}

fn stopped_with(o: &Outcome, stage: Stage, words: &[&str]) {
    match o {
        Outcome::Stopped {
            stage: s, message, ..
        } => {
            assert_eq!(*s, stage, "{message}");
            for w in words {
                assert!(message.contains(w), "'{w}' not in: {message}");
            }
        }
        other => panic!("expected a stop at {stage:?}, got {other:?}"),
    }
}

fn stable_within(o: &Outcome, limit: f64) {
    match o {
        Outcome::Stable { max_error, .. } => {
            assert!(*max_error < limit, "energy error {max_error}")
        }
        other => panic!("expected a stable run, got {other:?}"),
    }
}

#[test]
fn quick_matrix_has_no_silent_blow_up_and_each_regime_ends_as_expected() {
    let res = run_matrix(true, |r| {
        println!(
            "{} = {}: {:?} ({:.2} s)",
            r.cell.axis, r.cell.value, r.outcome, r.wall_s
        )
    });
    assert!(res.len() >= 20, "the slice covers every axis");
    for r in &res {
        assert!(
            !r.outcome.is_silent_blow_up(),
            "{} = {}: {:?}",
            r.cell.axis,
            r.cell.value,
            r.outcome
        );
        assert!(
            r.as_expected(),
            "{} = {}: {:?}, expected {:?}",
            r.cell.axis,
            r.cell.value,
            r.outcome,
            r.cell.expect
        );
    }
    // soft penalty below its limit: stable, energy balanced to 0.1%
    stable_within(find(&res, "penalty scale (soft)", "0.01"), 1e-3);
    stable_within(find(&res, "penalty scale (soft)", "0.1"), 1e-3);
    // a heavy mass ratio is stable: the soft penalty uses the smaller mass
    stable_within(find(&res, "mass ratio", "10000"), 1e-3);
    // nu = 0.499 is fine for a plane-stress shell; 0.5 is refused with the valid range
    stable_within(find(&res, "Poisson ratio", "0.499"), 1e-3);
    stopped_with(
        find(&res, "Poisson ratio", "0.5"),
        Stage::Input,
        &["poisson", "[0, 0.5)"],
    );
    // a node faster than the margin allows is stopped by the tunnelling guard
    stopped_with(
        find(&res, "impact speed", "300, margin 0.1 mm"),
        Stage::Run,
        &["margin", "step 1"],
    );
    // a scene cannot ask for a step above the critical one ...
    stopped_with(
        find(&res, "dt safety (scene)", "1.2"),
        Stage::Input,
        &["dt_safety", "(0, 1]"],
    );
    // ... and when forced, the runaway guard stops the run with the element
    stopped_with(
        find(&res, "dt safety (forced, free plate)", "2"),
        Stage::Run,
        &["energy runaway", "element"],
    );
    // warped quads are refused at input, naming the element and the limit
    stopped_with(
        find(&res, "warped quads", "0.5"),
        Stage::Input,
        &["warped", "quad", "0.05"],
    );
    // heavy Kelvin damping: the step shrinks, the balance (with dissipation) holds
    stable_within(find(&res, "Kelvin damping", "1e-4"), 0.05);
}
