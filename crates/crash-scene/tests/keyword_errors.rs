//! One test per kind of bad deck: the message names the file, the line (and the column
//! of the field when one is meant), the keyword and what is valid. Nothing the reader
//! does not support passes silently.

mod common;

use common::temp_dir;
use crash_scene::keyword::DeckOptions;
use crash_scene::{ErrorKind, InputError};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The fixed-format test deck with its mesh include inlined (line numbers are found
/// with `line_of`, so the deck may change).
fn base() -> String {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/keyword");
    let main = std::fs::read_to_string(dir.join("impact.k")).expect("deck");
    let mesh = std::fs::read_to_string(dir.join("impact-mesh.k")).expect("mesh");
    let mesh = mesh
        .trim_start_matches("*KEYWORD\n")
        .trim_end_matches("*END\n");
    main.replace("*INCLUDE\nimpact-mesh.k\n", mesh)
}

/// `base()` with one exact substring replaced (which must occur).
fn with(from: &str, to: &str) -> String {
    let b = base();
    assert!(b.contains(from), "the deck has no {from:?}");
    b.replacen(from, to, 1)
}

/// 1-based line of the first line of `text` that starts with `start`.
fn line_of(text: &str, start: &str) -> usize {
    text.lines()
        .position(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("no line starts with {start:?}"))
        + 1
}

static N: AtomicUsize = AtomicUsize::new(0);

/// Write `text` as deck.k in a fresh directory; load and build it.
fn run(text: &str, opts: DeckOptions) -> Result<crash_scene::Built, InputError> {
    let dir = temp_dir(&format!("deck-err-{}", N.fetch_add(1, Ordering::SeqCst)));
    let p = dir.join("deck.k");
    std::fs::write(&p, text).expect("write");
    crash_scene::load_input(&p, &opts)?
        .build()
        .map_err(InputError::from)
}

fn fail(text: &str) -> InputError {
    match run(text, DeckOptions::default()) {
        Ok(_) => panic!("the deck was accepted:\n{text}"),
        Err(e) => e,
    }
}

/// A deck error at `line` (and `column`, 0 for the whole card) naming `keyword` and
/// saying each of `parts`.
fn deck_err(e: &InputError, line: usize, column: usize, keyword: &str, parts: &[&str]) {
    let InputError::Deck(d) = e else {
        panic!("not a deck error: {e}")
    };
    let shown = d.to_string();
    assert_eq!((d.line, d.column), (line, column), "{shown}");
    assert_eq!(d.keyword, keyword, "{shown}");
    assert!(d.file.ends_with("deck.k"), "{shown}");
    let at = if column > 0 {
        format!("deck.k:{line}:{column}: *{keyword}: ")
    } else {
        format!("deck.k:{line}: *{keyword}: ")
    };
    assert!(shown.contains(&at), "{shown} lacks {at:?}");
    for p in parts {
        assert!(shown.contains(p), "message lacks {p:?}: {shown}");
    }
}

/// A scene error found by the scene's own checks, located at the deck card it came
/// from (deck file, line, no column).
fn scene_err(e: &InputError, kind: ErrorKind, line: usize, parts: &[&str]) {
    let InputError::Scene(s) = e else {
        panic!("not a scene error: {e}")
    };
    let shown = s.to_string();
    assert_eq!(s.kind, kind, "{shown}");
    assert_eq!((s.line, s.column), (line, 0), "{shown}");
    assert!(shown.contains(&format!("deck.k:{line}: ")), "{shown}");
    for p in parts {
        assert!(shown.contains(p), "message lacks {p:?}: {shown}");
    }
}

#[test]
fn the_base_deck_is_valid() {
    let b = run(&base(), DeckOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(b.bodies.len(), 2);
}

#[test]
fn unsupported_keyword_stops_with_its_name_and_line() {
    let t = with("*END", "*LOAD_BODY_Z\n         1\n*END");
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "*LOAD_BODY_Z"),
        0,
        "LOAD_BODY_Z",
        &["not supported", "keyword-input.md"],
    );
}

#[test]
fn unsupported_option_of_a_supported_keyword_is_named() {
    let t = with("*BOUNDARY_SPC_SET", "*BOUNDARY_SPC_SET_BIRTH_DEATH");
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "*BOUNDARY_SPC_SET"),
        0,
        "BOUNDARY_SPC_SET_BIRTH_DEATH",
        &["option _BIRTH_DEATH of *BOUNDARY_SPC_SET"],
    );
}

#[test]
fn unsupported_field_value_is_located_at_its_column() {
    // HGID (field 5, columns 41-50) of the plate's *PART card
    let t = with(
        "         1         1         1\nimpactor",
        "         1         1         1         0         3\nimpactor",
    );
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "plate") + 1,
        41,
        "PART",
        &["HGID: 3", "*HOURGLASS"],
    );
}

#[test]
fn bad_number_and_text_beyond_the_card_are_located() {
    let t = with("    0.0001\n", "    1.0x-4\n");
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "    1.0x-4"),
        1,
        "CONTROL_TERMINATION",
        &["ENDTIM", "`1.0x-4` is not a finite number"],
    );
    let t = with(
        "    0.0001\n",
        "    0.0001                                                                  9\n",
    );
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "    0.0001"),
        77,
        "CONTROL_TERMINATION",
        &["text beyond the card's 60 columns"],
    );
    let t = with("    0.0001\n", "\t0.0001\n");
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "\t0.0001"),
        1,
        "CONTROL_TERMINATION",
        &["a tab"],
    );
}

#[test]
fn too_many_comma_fields_are_refused() {
    let t = with("    0.0001\n", "0.0001,0,0,0,0,0,7\n");
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "0.0001,"),
        18,
        "CONTROL_TERMINATION",
        &["7 comma-separated fields, the card has 6"],
    );
}

#[test]
fn missing_include_is_reported_at_the_file_name() {
    let t = with("*END", "*INCLUDE\n  parts/missing.k\n*END");
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "  parts/missing.k"),
        3,
        "INCLUDE",
        &["cannot read", "parts/missing.k", "No such file"],
    );
}

#[test]
fn include_cycle_is_refused() {
    let dir = temp_dir("deck-cycle");
    std::fs::write(dir.join("a.k"), "*KEYWORD\n*INCLUDE\nb.k\n*END\n").expect("a");
    std::fs::write(dir.join("b.k"), "*KEYWORD\n*INCLUDE\na.k\n*END\n").expect("b");
    let e = crash_scene::load_input(&dir.join("a.k"), &DeckOptions::default()).expect_err("cycle");
    let s = e.to_string();
    assert!(
        s.contains("b.k:3:1: *INCLUDE:") && s.contains("a cycle"),
        "{s}"
    );
}

#[test]
fn node_shared_by_two_parts_names_both_parts() {
    // impactor element 101 uses plate node 13 instead of its own node 101
    let t = with(
        "     101       2     101     102     105     104",
        "     101       2      13     102     105     104",
    );
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "     101       2"),
        0,
        "ELEMENT_SHELL",
        &[
            "node 13 is shared by part 1",
            "and part 2",
            "separate meshes",
        ],
    );
}

#[test]
fn element_with_an_undefined_node_or_part_is_refused() {
    let t = with("     101       2     101", "     101       2     999");
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "     101       2"),
        0,
        "ELEMENT_SHELL",
        &["element 101 refers to node 999"],
    );
    let t = with("     101       2     101", "     101       9     101");
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "     101       9"),
        0,
        "ELEMENT_SHELL",
        &["part 9 is not defined"],
    );
}

#[test]
fn duplicate_node_id_names_the_first_definition() {
    let t = with("       2           -0.05", "       1           -0.05");
    let e = fail(&t);
    let first = line_of(&t, "       1            -0.1");
    deck_err(
        &e,
        line_of(&t, "       1           -0.05"),
        0,
        "NODE",
        &["node 1 is defined twice", &format!("deck.k:{first}")],
    );
}

#[test]
fn friction_is_refused_unless_the_user_ignores_it() {
    let t = with(
        "       0.0       0.0\n\n*END",
        "       0.2       0.0\n\n*END",
    );
    let e = fail(&t);
    let line = line_of(&t, "         2         1         3         3");
    deck_err(
        &e,
        line,
        0,
        "CONTACT_AUTOMATIC_SURFACE_TO_SURFACE",
        &["FS = 0.2", "frictionless", "--ignore-friction"],
    );
    let b = run(
        &t,
        DeckOptions {
            ignore_friction: true,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(b.notes.len(), 1, "{:?}", b.notes);
    assert!(
        b.notes[0].contains("FS = 0.2") && b.notes[0].contains("ignored"),
        "{:?}",
        b.notes
    );
}

#[test]
fn rigid_part_that_is_not_fully_constrained_is_refused() {
    // CON1 = 1 (x only): y is neither constrained nor prescribed
    let t = with(
        "       1.0       4.0       7.0",
        "       1.0       1.0       7.0",
    );
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "*MAT_RIGID") + 1,
        0,
        "MAT_RIGID",
        &["DOFs y are neither constrained", "no free rigid bodies"],
    );
}

#[test]
fn prescribed_node_with_free_dofs_is_refused() {
    // node 25 (plate corner) prescribed in z only
    let t = with("*LOAD_NODE_POINT +", "*BOUNDARY_PRESCRIBED_MOTION_NODE\n        25         3         0         1\n*LOAD_NODE_POINT +");
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "        25         3"),
        0,
        "BOUNDARY_PRESCRIBED_MOTION_NODE",
        &[
            "node 25: DOFs x, y, rx, ry, rz are neither prescribed nor held",
            "all six DOFs",
        ],
    );
}

#[test]
fn general_load_curve_on_the_motion_card_runs_as_a_time_table() {
    // curve 1 rises and falls back: no ramp, so the body carries the table itself
    let t = with(
        "               0.001                 1.0",
        "               0.001                 0.0",
    );
    let b = run(&t, DeckOptions::default()).expect("a general curve is accepted");
    let moving = b
        .bodies
        .iter()
        .find(|b| !b.def.programs.is_empty())
        .expect("a body with prescribed motion");
    let c = moving.def.programs[0].curve;
    assert_ne!(c, crash_core::NO_CURVE, "the program runs the curve");
    let table = &moving.def.curves[c as usize].points;
    assert_eq!(table.last().map(|p| p.1), Some(0.0), "{table:?}");
}

#[test]
fn material_values_are_checked_at_the_material_card() {
    let t = with(
        "         1    7800.0     2e+11       0.3",
        "         1    7800.0     2e+11       0.5",
    );
    let e = fail(&t);
    scene_err(
        &e,
        ErrorKind::Invalid,
        line_of(&t, "*MAT_ELASTIC") + 1,
        &["*MAT_ELASTIC 1", "poisson = 0.5", "[0, 0.5)"],
    );
}

#[test]
fn degenerate_element_is_reported_at_its_card() {
    // element 1 with two equal corners
    let t = with(
        "       1       1       1       2       7       6",
        "       1       1       1       2       2       6",
    );
    let e = fail(&t);
    scene_err(
        &e,
        ErrorKind::Geometry,
        line_of(&t, "       1       1       1"),
        &["*ELEMENT_SHELL 1"],
    );
}

#[test]
fn partial_initial_velocity_is_refused() {
    let t = with("*END", "*SET_NODE_LIST\n         5\n       101       102\n*INITIAL_VELOCITY\n         5\n       0.0       0.0      -1.0\n*END");
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "*INITIAL_VELOCITY") + 1,
        0,
        "INITIAL_VELOCITY",
        &["covers 2 of the 9 nodes of part 2"],
    );
}

#[test]
fn deck_without_termination_is_refused() {
    let t = with("*CONTROL_TERMINATION\n$#  endtim\n    0.0001\n", "");
    let e = fail(&t);
    let InputError::Deck(d) = &e else {
        panic!("{e}")
    };
    assert_eq!(
        (d.line, d.keyword.as_str()),
        (0, "CONTROL_TERMINATION"),
        "{e}"
    );
    assert!(
        e.to_string().contains("end time (ENDTIM) is required"),
        "{e}"
    );
}

#[test]
fn part_without_elements_and_undefined_references_are_refused() {
    let t = with(
        "*SECTION_SHELL_TITLE",
        "*PART\nempty\n         3         1         1\n*SECTION_SHELL_TITLE",
    );
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "empty") + 1,
        0,
        "PART",
        &["part 3 has no *ELEMENT_SHELL"],
    );
    let t = with(
        "         2         2         2\n",
        "         2         2         8\n",
    );
    let e = fail(&t);
    deck_err(
        &e,
        line_of(&t, "impactor") + 1,
        0,
        "PART",
        &["MID 8 is not defined"],
    );
}

#[test]
fn nodes_of_no_element_draw_a_note() {
    let t = with(
        "*ELEMENT_SHELL",
        "     999             1.0             1.0             1.0\n*ELEMENT_SHELL",
    );
    let b = run(&t, DeckOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(b.notes.len(), 1, "{:?}", b.notes);
    assert!(
        b.notes[0].contains("1 node(s) of the deck belong to no shell element")
            && b.notes[0].contains("node 999"),
        "{:?}",
        b.notes
    );
}
