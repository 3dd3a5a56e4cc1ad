//! `crash study --quick` in process: every verification case at its finest quick level
//! within its tolerance, the observed order of convergence at least 1.5 for the
//! frequencies and the deflection, and a report with one work–precision figure per case.

use crash_cli::study::cases::CASES;
use crash_cli::study::report::{self, figure_name, RunNote};
use crash_cli::study::verify::{run_suite, Selection};

#[test]
fn quick_study_meets_tolerances_and_orders_and_writes_its_report() {
    let results = run_suite(
        &Selection {
            quick: true,
            only: Vec::new(),
        },
        |l| println!("{l}"),
    );
    // every case ran for each of its element types
    let expected: usize = CASES.iter().map(|c| c.kinds.len()).sum();
    assert_eq!(results.len(), expected);
    let mut problems = Vec::new();
    for r in &results {
        let finest = r.mesh.last().expect("at least one level measured");
        println!(
            "{}: finest error {:.3e} (tolerance {:.1e}), orders {:?}",
            r.label(),
            finest.error,
            r.case.tolerance,
            r.mesh_orders()
        );
        assert!(
            finest.level.mesh == *r.case.quick.last().expect("quick ladder"),
            "{}: the finest quick level was not measured",
            r.label()
        );
        problems.extend(r.problems());
    }
    assert!(problems.is_empty(), "{problems:#?}");
    // frequencies and deflection must converge at order >= 1.5
    for id in ["fv52", "thin-plate", "cantilever"] {
        for r in results.iter().filter(|r| r.case.id == id) {
            let o = r.checked_order();
            assert!(o.is_some_and(|o| o >= 1.5), "{}: order {o:?}", r.label());
        }
    }
    // the report: markdown naming every case and a decodable figure per case
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("study-quick");
    let _ = std::fs::remove_dir_all(&dir);
    let note = RunNote {
        quick: true,
        threads: 1,
        total_wall_s: 0.0,
    };
    let files = report::write(&dir, &results, &note).expect("report written");
    assert_eq!(files.len(), CASES.len() + 1);
    let md = std::fs::read_to_string(dir.join("verification.md")).expect("markdown");
    assert!(md.starts_with("# Verification") && md.contains("do not edit by hand"));
    for c in CASES {
        assert!(
            md.contains(&format!("figures/{}", figure_name(c.id))),
            "{}",
            c.id
        );
        let img = crash_io::render::load_png(dir.join("figures").join(figure_name(c.id)))
            .expect("figure decodes");
        assert_eq!((img.width, img.height), (1000, 600));
        assert!(
            img.distinct_colours() > 3,
            "{}: the figure has content",
            c.id
        );
    }
}
