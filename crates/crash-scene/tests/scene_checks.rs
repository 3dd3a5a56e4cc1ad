//! The checks of issue 15, part 3: exact vector lengths, file references checked before
//! the build at the key that names them, capped reads, the memory estimate, output
//! intervals below the step, full key paths for missing keys.

mod common;

use common::*;
use crash_scene::{ErrorKind, SceneError};
use std::time::Instant;

/// Parse only (no build): the checks that must happen before anything is generated.
fn parse_error(text: &str) -> SceneError {
    match crash_scene::parse(text, "scene.toml") {
        Ok(_) => panic!("scene was accepted by parse:\n{text}"),
        Err(e) => e,
    }
}

#[test]
fn vector_with_four_components_is_refused_at_its_value() {
    // serde's [f64; 3] read three and dropped the fourth: velocity = [0, 0, -5, 1] passed
    let e = error(&with(
        "velocity = [0.0, 0.0, -5.0]",
        "velocity = [0.0, 0.0, -5.0, 1.0]",
    ));
    check(
        &e,
        ErrorKind::WrongType,
        24,
        12,
        "bodies[1].velocity",
        &["invalid length 4", "array of 3 numbers"],
    );
}

#[test]
fn every_fixed_length_array_is_checked() {
    let e = error(&format!("gravity = [0.0, 0.0, -9.81, 0.0]\n{BASE}"));
    check(
        &e,
        ErrorKind::WrongType,
        1,
        11,
        "gravity",
        &["invalid length 4"],
    );
    let e = error(&with("cells = [4, 4]", "cells = [4, 4, 3]"));
    check(
        &e,
        ErrorKind::WrongType,
        12,
        38,
        "bodies[0].plate.cells",
        &["invalid length 3", "array of 2"],
    );
    let e = error(&with("size = [0.4, 0.4]", "size = [0.4]"));
    check(
        &e,
        ErrorKind::WrongType,
        12,
        18,
        "bodies[0].plate.size",
        &["invalid length 1"],
    );
    let e = error(&format!(
        "{BASE}\n[curves.push]\npoints = [[0.0, 0.0], [1.0e-3, 1.0, 2.0]]\n"
    ));
    check(
        &e,
        ErrorKind::WrongType,
        27,
        23,
        "curves.push.points[1]",
        &["invalid length 3", "array of 2"],
    );
}

#[test]
fn missing_key_of_the_first_body_names_its_index() {
    // was `bodies.material is missing`
    let e = error(&with(
        "material = \"steel\"\nthickness = 2.0e-3",
        "thickness = 2.0e-3",
    ));
    check(
        &e,
        ErrorKind::Missing,
        8,
        1,
        "bodies[0].material",
        &["bodies[0].material is missing"],
    );
}

#[test]
fn missing_top_level_key_is_not_prefixed_by_the_first_key() {
    // was `name.end_time is missing`
    let e = error(&format!(
        "name = \"x\"\n{}",
        with("end_time = 1.0e-3\n", "")
    ));
    check(
        &e,
        ErrorKind::Missing,
        1,
        1,
        "end_time",
        &["end_time is missing"],
    );
}

#[test]
fn missing_key_in_an_inline_table_names_the_table() {
    let e = error(&with("radius = 0.1, level = 1", "level = 1"));
    check(
        &e,
        ErrorKind::Missing,
        22,
        10,
        "bodies[1].sphere.radius",
        &["bodies[1].sphere.radius is missing"],
    );
}

fn with_mesh(file: &str) -> String {
    with(
        "sphere = { radius = 0.1, level = 1 }",
        &format!("mesh = {{ file = \"{file}\" }}"),
    )
}

#[test]
fn missing_mesh_file_is_refused_by_parse_at_its_key() {
    let e = parse_error(&with_mesh("meshes/nope.msh"));
    check(
        &e,
        ErrorKind::Read,
        22,
        17,
        "bodies[1].mesh.file",
        &["cannot read meshes/nope.msh", "No such file"],
    );
    // the table form points at the file key's value too
    let text = format!(
        "{}[bodies.mesh]\nfile = \"nope.msh\"\n",
        with("sphere = { radius = 0.1, level = 1 }\n", "")
    );
    let e = parse_error(&text);
    check(
        &e,
        ErrorKind::Read,
        25,
        8,
        "bodies[1].mesh.file",
        &["nope.msh"],
    );
}

#[test]
fn device_and_directory_meshes_are_refused_without_reading() {
    let t = Instant::now();
    let e = parse_error(&with_mesh("/dev/zero"));
    check(
        &e,
        ErrorKind::Read,
        22,
        17,
        "bodies[1].mesh.file",
        &["/dev/zero is a character device, not a regular file"],
    );
    assert!(t.elapsed().as_secs_f64() < 5.0, "took {:?}", t.elapsed());
    let e = parse_error(&with_mesh("/"));
    check(
        &e,
        ErrorKind::Read,
        22,
        17,
        "bodies[1].mesh.file",
        &["is a directory"],
    );
}

#[test]
fn unreadable_scene_file_has_no_invented_location() {
    let e = crash_scene::load(std::path::Path::new("/no/such/scene.toml")).expect_err("missing");
    assert_eq!(e.kind, ErrorKind::Read);
    assert!(
        e.to_string()
            .starts_with("/no/such/scene.toml: cannot read the scene file"),
        "{e}"
    );
    // a device as the scene file is refused without reading it
    if std::path::Path::new("/dev/zero").exists() {
        let e = crash_scene::load(std::path::Path::new("/dev/zero")).expect_err("device");
        assert_eq!(
            e.to_string(),
            "/dev/zero: cannot read the scene file: /dev/zero is a character device, not a regular file"
        );
    }
}

/// A plate of 4430 x 4430 = 19.6 million quads: below the 20-million per-body guard.
fn big_plate() -> String {
    with("cells = [4, 4]", "cells = [4430, 4430]")
}

#[test]
fn plate_of_19_6_million_elements_is_refused_up_front_with_the_figure() {
    let t = Instant::now();
    let e = crash_scene::parse(&big_plate(), "scene.toml")
        .expect("parses")
        .with_memory_limit(16_000_000_000)
        .build()
        .expect_err("too large");
    check(
        &e,
        ErrorKind::TooLarge,
        12,
        1,
        "bodies[0].plate",
        &[
            "needs about 29.",
            "GB of memory",
            "19624980 elements",
            "16.0 GB this machine has available",
        ],
    );
    // refused before any mesh was generated (generating it takes minutes in debug)
    assert!(t.elapsed().as_secs_f64() < 2.0, "took {:?}", t.elapsed());
}

#[test]
fn plate_of_19_6_million_elements_is_refused_on_this_machine() {
    let need = crash_scene::memory::Counts {
        nodes: 4431 * 4431 + 42,
        tris: 80,
        quads: 4430 * 4430,
        ..Default::default()
    }
    .bytes();
    match crash_scene::memory::available() {
        Some(avail) if need > avail as f64 => {
            let e = error(&big_plate());
            assert_eq!(e.kind, ErrorKind::TooLarge, "{e}");
            assert!(e.to_string().contains("MemAvailable"), "{e}");
        }
        other => eprintln!("skipped: the machine has {other:?} bytes, the plate needs {need}"),
    }
}

#[test]
fn a_scene_that_fits_is_not_refused() {
    let b = crash_scene::parse(BASE, "scene.toml")
        .expect("parses")
        .with_memory_limit(100_000_000)
        .build()
        .expect("a few hundred elements fit in 100 MB");
    assert_eq!(b.bodies.len(), 2);
}

#[test]
fn output_interval_below_the_time_step_means_every_step_with_a_note() {
    let text = format!("output_interval = 1.0e-300\n{BASE}");
    let b = crash_scene::parse(&text, "scene.toml")
        .expect("valid")
        .build()
        .expect("builds");
    let dt = b.safety
        * b.bodies
            .iter()
            .map(crash_scene::margin::dt_estimate)
            .fold(f64::INFINITY, f64::min);
    assert_eq!(b.notes.len(), 1, "{:?}", b.notes);
    assert!(b.notes[0].contains("below the time step"), "{:?}", b.notes);
    assert!(b.notes[0].contains("every step"), "{:?}", b.notes);
    // raised to a hundredth of the step: at most ~100 frame times per step to count
    assert_eq!(
        b.output_interval,
        crash_scene::build::OUTPUT_FLOOR_FRACTION * dt
    );
    // an interval above the step is kept and draws no note
    let b = crash_scene::parse(BASE, "scene.toml")
        .expect("valid")
        .build()
        .expect("builds");
    assert!(b.notes.is_empty(), "{:?}", b.notes);
    assert_eq!(b.output_interval, 1.0e-5);
}
