//! The scene keys added for keyword decks, used directly in TOML: load curves (ramps
//! mapped onto the core ramps, anything else run as a time table), node-id
//! selectors, the shear factor, the point an initial spin is given about, several
//! ramps on one node, and the `[outputs]` requests.

mod common;

use common::*;
use crash_core::Vec3;
use crash_scene::ErrorKind;

fn build(text: &str) -> crash_scene::Built {
    crash_scene::parse(text, "scene.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
}

const PUSH: &str =
    "\n[[bodies.prescribe]]\nselect = \"all\"\nvelocity = [0.0, 0.0, -2.0]\ncurve = \"push\"\n";

#[test]
fn a_ramp_curve_on_prescribed_motion_becomes_the_core_ramp() {
    let text = format!(
        "{BASE}{PUSH}\n[curves.push]\npoints = [[0.0, 0.0], [1.0e-4, 0.5], [1.0e-3, 0.5]]\n"
    );
    let b = build(&text);
    let p = b.bodies[1].def.programs[0];
    assert_eq!(p.velocity, Vec3::new(0.0, 0.0, -1.0));
    assert_eq!(p.ramp, 1.0e-4);
}

#[test]
fn a_general_curve_runs_as_a_time_table() {
    // rises and falls: the body carries the table, the program points at it
    let text = format!(
        "{BASE}{PUSH}\n[curves.push]\npoints = [[0.0, 0.0], [1.0e-4, 1.0], [2.0e-4, 0.0]]\n"
    );
    let b = build(&text);
    let d = &b.bodies[1].def;
    let p = d.programs[0];
    assert_eq!(p.velocity, Vec3::new(0.0, 0.0, -2.0));
    assert_eq!(
        d.curves[p.curve as usize].points,
        vec![(0.0, 0.0), (1.0e-4, 1.0), (2.0e-4, 0.0)]
    );
    // a load that is a ramp still runs as one (t0, t1), without a table
    let load = format!("{BASE}\n[[bodies.load]]\nselect = \"all\"\nforce = [0.0, 0.0, -8.0]\ncurve = \"late\"\n\n[curves.late]\npoints = [[0.0, 0.0], [1.0e-4, 0.0], [2.0e-4, 1.0]]\n");
    let b = build(&load);
    let l = b.bodies[1].def.loads[0];
    assert_eq!(
        (l.t0, l.t1, l.curve),
        (1.0e-4, 2.0e-4, crash_core::NO_CURVE)
    );
}

#[test]
fn curve_names_and_points_are_checked_when_the_scene_is_parsed() {
    let e = crash_scene::parse(&format!("{BASE}{PUSH}"), "scene.toml").expect_err("no curve");
    check(
        &e,
        ErrorKind::Reference,
        29,
        9,
        "bodies[1].prescribe[0].curve",
        &["no curve of that name", "[curves.NAME]"],
    );
    let text = format!("{BASE}{PUSH}\n[curves.push]\npoints = [[0.0, 0.0], [0.0, 1.0]]\n");
    let e = crash_scene::parse(&text, "scene.toml").expect_err("times");
    check(
        &e,
        ErrorKind::Invalid,
        32,
        23,
        "curves.push.points[1]",
        &["times must increase"],
    );
    let text = format!("{BASE}{PUSH}ramp = 1.0e-4\n\n[curves.push]\npoints = [[0.0, 1.0]]\n");
    let e = error(&text);
    check(
        &e,
        ErrorKind::Invalid,
        30,
        1,
        "bodies[1].prescribe[0].ramp",
        &["either ramp or curve"],
    );
}

#[test]
fn node_ids_select_nodes_of_mesh_files_only() {
    let text = with("select = \"x-\"", "select = { nodes = [1, 2] }");
    let e = error(&text);
    check(
        &e,
        ErrorKind::Invalid,
        15,
        20,
        "bodies[0].fix[0].select.nodes",
        &["nodes of an imported mesh"],
    );
}

#[test]
fn shear_factor_scales_the_transverse_shear_stiffness() {
    let b = build(&with(
        "thickness = 2.0e-3",
        "thickness = 2.0e-3\nshear_factor = 1.0",
    ));
    let g = 200.0e9 / 2.6;
    assert!((b.bodies[0].def.section.shear - g * 2.0e-3).abs() < 1e-6 * g * 2.0e-3);
    let d = build(BASE);
    assert_eq!(
        d.bodies[0].def.section.shear,
        crash_core::Section::new(d.bodies[0].def.section.material, 2.0e-3).shear
    );
    let e = error(&with(
        "thickness = 2.0e-3",
        "thickness = 2.0e-3\nshear_factor = 1.5",
    ));
    check(
        &e,
        ErrorKind::Invalid,
        12,
        16,
        "bodies[0].shear_factor",
        &["(0, 1]"],
    );
}

#[test]
fn a_spin_is_given_about_the_stated_point() {
    let text = with(
        "velocity = [0.0, 0.0, -5.0]",
        "velocity = [0.0, 0.0, -5.0]\nangular_velocity = [0.0, 0.0, 10.0]\nangular_velocity_centre = [0.1, 0.0, 0.2]",
    );
    let b = build(&text);
    let s = &b.bodies[1];
    let c = Vec3::new(0.1, 0.0, 0.2);
    for (x, v) in s.state.x.iter().zip(&s.state.v) {
        let expect = Vec3::new(0.0, 0.0, -5.0) + Vec3::new(0.0, 0.0, 10.0).cross(&(x - c));
        assert!((v - expect).norm() < 1e-12);
    }
}

#[test]
fn loads_with_different_ramps_on_one_node_are_both_kept() {
    let text = format!("{BASE}\n[[bodies.load]]\nselect = \"all\"\nforce = [0.0, 0.0, -1.0]\n\n[[bodies.load]]\nselect = \"all\"\nforce = [1.0, 0.0, 0.0]\nstart = 1.0e-4\nramp = 1.0e-4\n");
    let b = build(&text);
    let s = &b.bodies[1];
    assert_eq!(s.def.loads.len(), 2 * s.node_count());
    assert_eq!(b.info[1].loaded_nodes, s.node_count());
}

#[test]
fn output_requests_are_checked_and_carried() {
    let text = format!("{BASE}\n[outputs]\nglstat = 1.0e-5\nrcforc = 2.0e-5\n");
    let b = build(&text);
    assert_eq!(
        (b.outputs.glstat, b.outputs.rcforc, b.outputs.matsum),
        (Some(1.0e-5), Some(2.0e-5), None)
    );
    let e = error(&format!("{BASE}\n[outputs]\nglstat = 0.0\n"));
    check(&e, ErrorKind::Invalid, 27, 10, "outputs.glstat", &["> 0"]);
    let e = error(&format!(
        "{BASE}\n[[outputs.history]]\nbody = \"ghost\"\nnodes = [1]\n"
    ));
    check(
        &e,
        ErrorKind::Reference,
        27,
        8,
        "outputs.history[0].body",
        &["no body of that name"],
    );
    let e = error(&format!(
        "{BASE}\n[[outputs.history]]\nbody = \"ball\"\nnodes = [1]\n"
    ));
    check(
        &e,
        ErrorKind::Invalid,
        28,
        9,
        "outputs.history[0].nodes",
        &["generated mesh"],
    );
}

#[test]
fn frame_precision_and_compression_are_checked_and_carried() {
    let b = build(BASE);
    assert_eq!(
        (b.outputs.frames_f32, b.outputs.frames_uncompressed),
        (false, false)
    );
    let b = build(&format!(
        "{BASE}\n[outputs]\nprecision = \"f32\"\ncompression = \"none\"\n"
    ));
    assert_eq!(
        (b.outputs.frames_f32, b.outputs.frames_uncompressed),
        (true, true)
    );
    let b = build(&format!(
        "{BASE}\n[outputs]\nprecision = \"f64\"\ncompression = \"zlib\"\n"
    ));
    assert_eq!(
        (b.outputs.frames_f32, b.outputs.frames_uncompressed),
        (false, false)
    );
    let e = error(&format!("{BASE}\n[outputs]\nprecision = \"half\"\n"));
    check(
        &e,
        ErrorKind::Invalid,
        27,
        13,
        "outputs.precision",
        &["\"f64\"", "\"f32\""],
    );
    let e = error(&format!("{BASE}\n[outputs]\ncompression = \"lz4\"\n"));
    check(
        &e,
        ErrorKind::Invalid,
        27,
        15,
        "outputs.compression",
        &["\"zlib\"", "\"none\""],
    );
}
