//! One test per kind of bad input: the message names file, line, column, key and what
//! is valid.

mod common;

use common::*;
use crash_scene::{ErrorKind, Overrides};

#[test]
fn toml_syntax_error_is_located_and_names_the_key() {
    let e = error(&with("thickness = 2.0e-3", "thickness = 2.0e-3 mm"));
    check(
        &e,
        ErrorKind::Syntax,
        11,
        13,
        "thickness",
        &["scene.toml:11:13", "invalid TOML", "quoted"],
    );
}

#[test]
fn unknown_top_level_key_lists_the_valid_keys() {
    let e = error(&with("end_time = 1.0e-3", "end_tme = 1.0e-3"));
    check(
        &e,
        ErrorKind::UnknownKey,
        1,
        1,
        "end_tme",
        &["unknown key `end_tme`", "end_time", "gravity", "dt_safety"],
    );
}

#[test]
fn unknown_body_key_is_located_and_lists_body_keys_and_shapes() {
    let e = error(&with("velocity = [0.0", "speed = [0.0"));
    check(
        &e,
        ErrorKind::UnknownKey,
        24,
        1,
        "bodies[1].speed",
        &[
            "unknown key `speed`",
            "velocity",
            "angular_velocity",
            "plate, sphere, cylinder, box, mesh",
        ],
    );
}

#[test]
fn unknown_shape_is_an_unknown_key_naming_the_shapes() {
    let e = error(&with(
        "sphere = { radius = 0.1, level = 1 }",
        "cone = { radius = 0.1 }",
    ));
    check(
        &e,
        ErrorKind::UnknownKey,
        22,
        1,
        "bodies[1].cone",
        &["unknown key `cone`", "plate, sphere, cylinder, box, mesh"],
    );
}

#[test]
fn unknown_key_inside_a_shape_table_lists_that_shapes_keys() {
    let e = error(&with("radius = 0.1, level = 1", "radius = 0.1, lvl = 1"));
    check(
        &e,
        ErrorKind::UnknownKey,
        22,
        26,
        "bodies[1].sphere.lvl",
        &["unknown key `lvl`", "radius, level, cubed, element_size"],
    );
}

#[test]
fn wrong_type_names_the_expected_type() {
    let e = error(&with("thickness = 2.0e-3", "thickness = \"thin\""));
    check(
        &e,
        ErrorKind::WrongType,
        11,
        13,
        "bodies[0].thickness",
        &["bodies[0].thickness = \"thin\"", "expected a number"],
    );
}

#[test]
fn vector_of_wrong_length_is_a_type_error() {
    let e = error(&with(
        "velocity = [0.0, 0.0, -5.0]",
        "velocity = [0.0, -5.0]",
    ));
    check(
        &e,
        ErrorKind::WrongType,
        24,
        12,
        "bodies[1].velocity",
        &["3"],
    );
}

#[test]
fn missing_required_key_is_reported_at_its_table() {
    let e = error(&with("thickness = 1.0e-3\n", ""));
    check(
        &e,
        ErrorKind::Missing,
        18,
        1,
        "bodies[1].thickness",
        &["bodies[1].thickness is missing", "required"],
    );
}

#[test]
fn missing_end_time_is_reported() {
    let e = error(&with("end_time = 1.0e-3\n", ""));
    assert_eq!(e.kind, ErrorKind::Missing, "{e}");
    assert_eq!(e.key, "end_time", "{e}");
    assert!(
        e.to_string()
            .starts_with("scene.toml:1:1: end_time is missing"),
        "{e}"
    );
}

#[test]
fn unknown_material_name_lists_the_defined_ones() {
    let e = error(&with(
        "material = \"steel\"\nthickness = 1.0e-3",
        "material = \"stel\"\nthickness = 1.0e-3",
    ));
    check(
        &e,
        ErrorKind::Reference,
        20,
        12,
        "bodies[1].material",
        &[
            "bodies[1].material = \"stel\"",
            "no material of that name",
            "defined: steel",
        ],
    );
}

#[test]
fn poisson_ratio_of_one_half_is_refused_with_the_valid_range() {
    let e = error(&with("poisson = 0.3", "poisson = 0.5"));
    assert_eq!(
        e.to_string(),
        "scene.toml:6:11: materials.steel.poisson = 0.5: must be in [0, 0.5)"
    );
    check(
        &e,
        ErrorKind::Invalid,
        6,
        11,
        "materials.steel.poisson",
        &[],
    );
}

#[test]
fn negative_density_is_refused_with_its_unit() {
    let e = error(&with("density = 7800.0", "density = -7800.0"));
    check(
        &e,
        ErrorKind::Invalid,
        4,
        11,
        "materials.steel.density",
        &["= -7800.0", "> 0", "kg/m^3"],
    );
}

#[test]
fn lame_pair_is_accepted_and_a_bad_shear_modulus_refused() {
    let lame = with(
        "young = 200.0e9\npoisson = 0.3",
        "lambda1 = 115.4e9\nlambda2 = 76.9e9",
    );
    let s = crash_scene::parse(&lame, "scene.toml").expect("Lamé pair is valid");
    let m = s.materials["steel"];
    // lambda = E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)) for E = 200 GPa, nu = 0.3
    assert!((m.young - 200.0e9).abs() < 0.1e9, "{}", m.young);
    assert!((m.poisson - 0.3).abs() < 1e-3, "{}", m.poisson);
    let e = error(&lame.replace("lambda2 = 76.9e9", "lambda2 = 0.0"));
    check(
        &e,
        ErrorKind::Invalid,
        6,
        11,
        "materials.steel.lambda2",
        &["> 0"],
    );
}

#[test]
fn half_given_material_pair_says_what_is_missing() {
    let e = error(&with("poisson = 0.3\n", ""));
    check(
        &e,
        ErrorKind::Missing,
        3,
        1,
        "materials.steel.poisson",
        &["young needs poisson"],
    );
    let e = error(&with("poisson = 0.3", "poisson = 0.3\nlambda1 = 1.0e9"));
    check(
        &e,
        ErrorKind::Invalid,
        7,
        1,
        "materials.steel.lambda1",
        &["either young and poisson, or lambda1 and lambda2"],
    );
}

#[test]
fn non_positive_thickness_is_refused() {
    let e = error(&with("thickness = 2.0e-3", "thickness = 0.0"));
    check(
        &e,
        ErrorKind::Invalid,
        11,
        13,
        "bodies[0].thickness",
        &["bodies[0].thickness = 0.0", "must be finite and > 0 (m)"],
    );
}

#[test]
fn negative_cell_count_is_refused() {
    let e = error(&with("cells = [4, 4]", "cells = [-3, 4]"));
    check(
        &e,
        ErrorKind::Invalid,
        12,
        39,
        "bodies[0].plate.cells[0]",
        &["bodies[0].plate.cells[0] = -3", "integer >= 1"],
    );
}

#[test]
fn cells_and_element_size_together_or_neither_are_refused() {
    let e = error(&with(
        "cells = [4, 4]",
        "cells = [4, 4], element_size = 0.1",
    ));
    check(
        &e,
        ErrorKind::Invalid,
        12,
        61,
        "bodies[0].plate.element_size",
        &["either cells or element_size"],
    );
    let e = error(&with(", cells = [4, 4]", ""));
    check(
        &e,
        ErrorKind::Missing,
        12,
        9,
        "bodies[0].plate.cells",
        &["cells or element_size"],
    );
}

#[test]
fn sphere_level_out_of_range_is_refused() {
    let e = error(&with("level = 1", "level = 12"));
    check(
        &e,
        ErrorKind::Invalid,
        22,
        34,
        "bodies[1].sphere.level",
        &["[0, 8]"],
    );
}

#[test]
fn quad_sphere_is_refused() {
    let e = error(&with("sphere = {", "element = \"quad\"\nsphere = {"));
    check(
        &e,
        ErrorKind::Invalid,
        22,
        11,
        "bodies[1].element",
        &["triangles", "\"tri\""],
    );
}

#[test]
fn unknown_element_type_is_refused() {
    let e = error(&with("sphere = {", "element = \"hex\"\nsphere = {"));
    check(
        &e,
        ErrorKind::Invalid,
        22,
        11,
        "bodies[1].element",
        &["\"tri\" or \"quad\""],
    );
}

#[test]
fn two_shapes_in_one_body_are_refused() {
    let e = error(&with(
        "position = [0.0, 0.0, 0.2]",
        "position = [0.0, 0.0, 0.2]\nbox = { size = [1.0, 1.0, 1.0], cells = 2 }",
    ));
    check(
        &e,
        ErrorKind::Invalid,
        24,
        1,
        "bodies[1].box",
        &["two shapes (sphere and box)", "exactly one"],
    );
}

#[test]
fn body_without_shape_is_refused() {
    let e = error(&with("sphere = { radius = 0.1, level = 1 }\n", ""));
    check(
        &e,
        ErrorKind::Missing,
        18,
        1,
        "bodies[1].shape",
        &["no shape", "plate, sphere, cylinder, box, mesh"],
    );
}

#[test]
fn unknown_selector_lists_the_valid_ones() {
    let e = error(&with("select = \"x-\"", "select = \"x*\""));
    check(
        &e,
        ErrorKind::Invalid,
        15,
        10,
        "bodies[0].fix[0].select",
        &["unknown selector", "\"x-\"", "min = [x, y, z]"],
    );
}

#[test]
fn box_selector_that_selects_nothing_is_refused() {
    let e = error(&with(
        "select = \"x-\"",
        "select = { min = [5.0, 5.0, 5.0], max = [6.0, 6.0, 6.0] }",
    ));
    check(
        &e,
        ErrorKind::Invalid,
        15,
        10,
        "bodies[0].fix[0].select",
        &["selects no node", "-0.2000"],
    );
}

#[test]
fn box_selector_with_max_below_min_is_refused() {
    let e = error(&with(
        "select = \"x-\"",
        "select = { min = [0.0, 0.0, 0.0], max = [-1.0, 1.0, 1.0] }",
    ));
    check(
        &e,
        ErrorKind::Invalid,
        15,
        41,
        "bodies[0].fix[0].select.max",
        &["must be >= min"],
    );
}

#[test]
fn unknown_dof_names_the_valid_ones() {
    let e = error(&with("dofs = \"all\"", "dofs = [\"x\", \"q\"]"));
    check(
        &e,
        ErrorKind::Invalid,
        16,
        14,
        "bodies[0].fix[0].dofs[1]",
        &["unknown DOF", "\"rx\"", "\"translations\""],
    );
}

#[test]
fn non_positive_end_time_is_refused() {
    let e = error(&with("end_time = 1.0e-3", "end_time = 0.0"));
    assert_eq!(
        e.to_string(),
        "scene.toml:1:12: end_time = 0.0: must be finite and > 0 (s)"
    );
}

#[test]
fn non_positive_end_time_override_is_refused_and_a_good_one_applies() {
    let s = crash_scene::parse(BASE, "scene.toml").expect("valid");
    let e = s
        .clone()
        .with_overrides(Overrides {
            end_time: Some(-1.0),
            ..Default::default()
        })
        .expect_err("negative end time");
    check(
        &e,
        ErrorKind::Invalid,
        1,
        1,
        "end_time",
        &["-1 (given on the command line)", "> 0"],
    );
    let b = s
        .with_overrides(Overrides {
            end_time: Some(2.0e-3),
            ..Default::default()
        })
        .expect("valid")
        .build()
        .expect("builds");
    assert_eq!(b.end_time, 2.0e-3);
    // the default output interval follows the end time: 100 frames
    assert_eq!(b.output_interval, 2.0e-5);
}

#[test]
fn dt_safety_above_one_is_refused() {
    let e = error(&format!("dt_safety = 1.5\n{BASE}"));
    check(&e, ErrorKind::Invalid, 1, 13, "dt_safety", &["(0, 1]"]);
}

#[test]
fn unknown_penalty_kind_is_refused() {
    let e = error(&format!("{BASE}\n[contact]\npenalty = \"hard\"\n"));
    check(
        &e,
        ErrorKind::Invalid,
        27,
        11,
        "contact.penalty",
        &["\"soft\" or \"element\""],
    );
}

#[test]
fn unknown_contact_pass_and_segments_with_the_element_penalty_are_refused() {
    let e = error(&format!("{BASE}\n[contact]\npass = \"points\"\n"));
    assert_eq!(e.kind, ErrorKind::Invalid, "{e}");
    assert!(e.to_string().contains("contact.pass"), "{e}");
    let e = error(&format!(
        "{BASE}\n[contact]\npass = \"segments\"\npenalty = \"element\"\n"
    ));
    assert_eq!(e.kind, ErrorKind::Invalid, "{e}");
    assert!(e.to_string().contains("penalty = \"soft\""), "{e}");
}

#[test]
fn unknown_segment_sides_and_sides_under_the_node_passes_are_refused() {
    let e = error(&format!(
        "{BASE}\n[contact]\npass = \"segments\"\nsides = \"one\"\n"
    ));
    assert_eq!(e.kind, ErrorKind::Invalid, "{e}");
    assert!(
        e.to_string().contains("\"auto\", \"finer\" or \"both\""),
        "{e}"
    );
    let e = error(&format!("{BASE}\n[contact]\nsides = \"both\"\n"));
    assert_eq!(e.kind, ErrorKind::Invalid, "{e}");
    assert!(e.to_string().contains("contact.sides"), "{e}");
    assert!(e.to_string().contains("pass = \"segments\" only"), "{e}");
}

#[test]
fn duplicate_body_name_is_refused() {
    let e = error(&with("name = \"ball\"", "name = \"plate\""));
    check(
        &e,
        ErrorKind::Invalid,
        19,
        8,
        "bodies[1].name",
        &["bodies[0] has the same name"],
    );
}

#[test]
fn scene_without_bodies_is_refused() {
    let text = BASE.split("[[bodies]]").next().expect("head");
    let e = error(text);
    assert_eq!(e.kind, ErrorKind::Missing, "{e}");
    assert!(e.to_string().contains("at least one [[bodies]]"), "{e}");
}

#[test]
fn zero_rotation_axis_is_refused() {
    let e = error(&with(
        "position = [0.0, 0.0, 0.2]",
        "position = [0.0, 0.0, 0.2]\nrotation = { axis = [0.0, 0.0, 0.0], angle = 30.0 }",
    ));
    check(
        &e,
        ErrorKind::Invalid,
        24,
        21,
        "bodies[1].rotation.axis",
        &["non-zero"],
    );
}

#[test]
fn negative_mass_damping_is_refused() {
    let e = error(&with(
        "position = [0.0, 0.0, 0.2]",
        "position = [0.0, 0.0, 0.2]\nmass_damping = -1.0",
    ));
    check(
        &e,
        ErrorKind::Invalid,
        24,
        16,
        "bodies[1].mass_damping",
        &[">= 0 (1/s)"],
    );
}

#[test]
fn load_without_force_or_moment_is_refused() {
    let e = error(&format!("{BASE}\n[[bodies.load]]\nselect = \"all\"\n"));
    check(
        &e,
        ErrorKind::Missing,
        26,
        1,
        "bodies[1].load[0].force",
        &["force (N) and/or moment (N m)"],
    );
}

#[test]
fn bodies_interpenetrating_at_start_are_refused() {
    // the ball's lowest node (z = -0.1 + 0.2 - 0.1 = 0) lies in the plate's mid-plane
    let e = error(&with(
        "position = [0.0, 0.0, 0.2]",
        "position = [0.0, 0.0, 0.1]",
    ));
    check(
        &e,
        ErrorKind::Geometry,
        23,
        1,
        "bodies[1].position",
        &[
            "interpenetrate at t = 0",
            "\"plate\"",
            "\"ball\"",
            "1.5000e-3",
        ],
    );
}

#[test]
fn overlapping_boxes_without_penetration_are_accepted() {
    // lowest node 0.1 m + 1.6 mm - 0.1 m above the plate's mid-plane: boxes overlap, no contact
    let text = with(
        "position = [0.0, 0.0, 0.2]",
        "position = [0.0, 0.0, 0.1016]",
    );
    let b = crash_scene::parse(&text, "scene.toml")
        .expect("valid")
        .build()
        .expect("builds");
    assert_eq!(b.bodies.len(), 2);
}

/// The run directory is out/<name>: a name that is a path (`../../x`, absolute, `..`,
/// with a backslash or a control character) must not reach the file system.
#[test]
fn scene_name_that_would_leave_the_output_root_is_refused() {
    for bad in [
        "../../x",
        "/tmp/x",
        "..",
        ".",
        "",
        "a\\\\b",
        "C:x",
        "a\\u0000b",
    ] {
        let text = format!("name = \"{bad}\"\n{BASE}");
        let e = error(&text);
        let shown = e.to_string();
        assert_eq!(e.kind, ErrorKind::Invalid, "{bad:?}: {shown}");
        assert_eq!((e.line, e.key.as_str()), (1, "name"), "{bad:?}: {shown}");
        assert!(
            shown.starts_with("scene.toml:1:") && shown.contains("one plain file name"),
            "{bad:?}: {shown}"
        );
    }
    for good in ["sphere-on-plate", "run 2", "ten_spheres.v2", "Kugel-Ü"] {
        let text = format!("name = \"{good}\"\n{BASE}");
        let s = crash_scene::parse(&text, "scene.toml").unwrap_or_else(|e| panic!("{good}: {e}"));
        assert_eq!(s.name, good);
    }
}
