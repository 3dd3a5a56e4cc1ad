//! What a valid scene builds into: defaults, placement (rotation convention), initial
//! motion about the centre of mass, selectors, DOF masks, prescribed motion, loads,
//! mesh densities, the derived contact margin and the scene hash.

mod common;

use common::*;
use crash_core::body::{dof, NO_PROGRAM};
use crash_core::contact::{ContactPass, PenaltyKind, SegmentSides};
use crash_core::Vec3;
use crash_scene::margin::{MARGIN_ELEMENT_FRACTION, MARGIN_STEPS};

fn build(text: &str) -> crash_scene::Built {
    crash_scene::parse(text, "scene.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn defaults_are_applied() {
    let b = build(BASE);
    assert_eq!(b.name, "scene");
    assert_eq!(b.safety, 0.9);
    assert_eq!(b.gravity, Vec3::zeros());
    assert_eq!(b.energy_limit, 0.05);
    assert_eq!(b.output_interval, 1.0e-5);
    assert!(b.contact.enabled && b.margin_derived);
    assert_eq!(b.contact.penalty, PenaltyKind::Soft);
    assert_eq!(b.contact.penalty_scale, 0.1);
    assert_eq!(b.contact.damping_ratio, 0.0);
    assert_eq!(
        b.bodies.iter().map(|x| x.def.id).collect::<Vec<_>>(),
        vec![0, 1]
    );
    assert!(b
        .bodies
        .iter()
        .all(|x| x.def.contact && !x.def.self_contact && x.def.mass_damping == 0.0));
    assert_eq!(b.run_config().end_time, 1.0e-3);
}

#[test]
fn contact_pass_is_nodes_by_default_and_segments_when_given() {
    assert_eq!(build(BASE).contact.pass, ContactPass::Nodes);
    let b = build(&format!("{BASE}\n[contact]\npass = \"segments\"\n"));
    assert_eq!(b.contact.pass, ContactPass::Segments);
    // one side where one surface is clearly finer, else both, unless asked
    assert_eq!(b.contact.sides, SegmentSides::Auto);
    for (given, want) in [("both", SegmentSides::Both), ("finer", SegmentSides::Finer)] {
        let b = build(&format!(
            "{BASE}\n[contact]\npass = \"segments\"\nsides = \"{given}\"\n"
        ));
        assert_eq!(b.contact.sides, want);
    }
}

#[test]
fn given_globals_and_contact_keys_are_kept() {
    let text = format!(
        "name = \"run-7\"\ndt_safety = 0.5\ngravity = [0.0, 0.0, -9.81]\noutput_interval = 2.0e-4\nenergy_limit = 0.1\n{BASE}\n[contact]\nenabled = false\nmargin = 0.003\npenalty_scale = 0.2\npenalty = \"element\"\ndamping_ratio = 0.1\n"
    );
    let b = build(&text);
    assert_eq!(
        (b.name.as_str(), b.safety, b.output_interval, b.energy_limit),
        ("run-7", 0.5, 2.0e-4, 0.1)
    );
    assert_eq!(b.gravity, Vec3::new(0.0, 0.0, -9.81));
    assert!(!b.contact.enabled && !b.margin_derived);
    assert_eq!(
        (
            b.contact.margin,
            b.contact.penalty_scale,
            b.contact.damping_ratio
        ),
        (0.003, 0.2, 0.1)
    );
    assert_eq!(b.contact.penalty, PenaltyKind::Element);
}

#[test]
fn scene_hash_is_fnv1a_of_the_file_bytes() {
    let b = build(BASE);
    let mut h = crash_core::hash::Fnv::default();
    h.bytes(BASE.as_bytes());
    assert_eq!(b.scene_hash, h.finish());
    // the FNV-1a 64 reference value of "a" pins the algorithm
    let mut a = crash_core::hash::Fnv::default();
    a.bytes(b"a");
    assert_eq!(a.finish(), 0xaf63_dc4c_8601_ec8c);
    let other = build(&BASE.replace("-5.0]", "-5.1]"));
    assert_ne!(other.scene_hash, b.scene_hash);
}

#[test]
fn rotation_is_right_handed_in_degrees_and_applied_before_the_position() {
    // plate 0.4 x 0.2 rotated +90 degrees about x: local +y goes to global +z
    let text = with(
        "plate = { size = [0.4, 0.4], cells = [4, 4] }",
        "plate = { size = [0.4, 0.2], cells = [4, 2] }\nrotation = { axis = [2.0, 0.0, 0.0], angle = 90.0 }\nposition = [1.0, 2.0, 3.0]",
    );
    let b = build(&text);
    let p = &b.bodies[0];
    // node 14 = (i 4, j 2) is the local corner (0.2, 0.1, 0)
    let x = p.def.x0[14];
    assert!((x - Vec3::new(1.2, 2.0, 3.1)).norm() < 1e-12, "{x}");
    // x- stays the local edge x = -0.2 after rotation: 3 nodes, all at global x = 0.8
    let fixed: Vec<usize> = (0..p.node_count())
        .filter(|&i| p.def.fixed[i] != 0)
        .collect();
    assert_eq!(fixed.len(), 3);
    assert!(fixed
        .iter()
        .all(|&i| (p.def.x0[i].x - 0.8).abs() < 1e-12 && p.def.fixed[i] == dof::ALL));
}

#[test]
fn initial_spin_is_about_the_centre_of_mass() {
    let text = with(
        "velocity = [0.0, 0.0, -5.0]",
        "velocity = [1.0, 0.0, 0.0]\nangular_velocity = [0.0, 0.0, 10.0]",
    );
    let b = build(&text);
    let s = &b.bodies[1];
    let com = s.centre_of_mass();
    assert!((com - Vec3::new(0.0, 0.0, 0.2)).norm() < 1e-12);
    let m = s.total_mass();
    assert!((s.linear_momentum() - Vec3::new(m, 0.0, 0.0)).norm() < 1e-12 * m);
    for i in 0..s.node_count() {
        let expect =
            Vec3::new(1.0, 0.0, 0.0) + Vec3::new(0.0, 0.0, 10.0).cross(&(s.state.x[i] - com));
        assert!((s.state.v[i] - expect).norm() < 1e-12, "node {i}");
        assert_eq!(s.state.w[i], Vec3::new(0.0, 0.0, 10.0));
    }
}

#[test]
fn box_selector_and_dof_list_fix_exactly_the_named_bits() {
    let text = with(
        "select = \"x-\"\ndofs = \"all\"",
        "select = { min = [-0.21, -0.21, -0.01], max = [0.21, -0.19, 0.01] }\ndofs = [\"x\", \"z\", \"rx\"]",
    );
    let b = build(&text);
    let p = &b.bodies[0];
    let fixed: Vec<usize> = (0..p.node_count())
        .filter(|&i| p.def.fixed[i] != 0)
        .collect();
    // the y- edge of a 4 x 4 plate: nodes 0..=4
    assert_eq!(fixed, vec![0, 1, 2, 3, 4]);
    assert!(fixed
        .iter()
        .all(|&i| p.def.fixed[i] == dof::X | dof::Z | dof::RX));
}

#[test]
fn selector_lists_are_unions_and_named_sets_map_to_masks() {
    let text = with(
        "select = \"x-\"\ndofs = \"all\"",
        "select = [\"x-\", \"x+\", \"y-\", \"y+\"]\ndofs = \"rotations\"",
    );
    let b = build(&text);
    let p = &b.bodies[0];
    assert_eq!(
        p.def.fixed.iter().filter(|&&f| f == dof::ROTATIONS).count(),
        16
    );
    assert_eq!(p.def.fixed.iter().filter(|&&f| f == 0).count(), 9);
    assert_eq!(b.info[0].fixed_nodes, 16);
}

#[test]
fn prescribed_velocity_with_ramp_starts_at_rest_and_without_ramp_at_full_speed() {
    let text = format!("{BASE}\n[[bodies.prescribe]]\nselect = \"z-\"\nvelocity = [0.0, 0.0, -2.0]\nramp = 1.0e-4\n");
    let b = build(&text);
    let s = &b.bodies[1];
    let moved: Vec<usize> = (0..s.node_count())
        .filter(|&i| s.def.program[i] != NO_PROGRAM)
        .collect();
    // z- of a level-1 icosphere is one node (the lowest)
    assert_eq!(moved.len(), 1);
    let n = moved[0];
    assert_eq!(s.def.fixed[n], dof::ALL);
    assert_eq!(s.def.programs[0].velocity, Vec3::new(0.0, 0.0, -2.0));
    assert_eq!(s.def.programs[0].ramp, 1.0e-4);
    assert_eq!(s.state.v[n], Vec3::zeros());
    let text =
        format!("{BASE}\n[[bodies.prescribe]]\nselect = \"all\"\nvelocity = [0.0, 0.0, -2.0]\n");
    let b = build(&text);
    assert!(b.bodies[1]
        .state
        .v
        .iter()
        .all(|v| *v == Vec3::new(0.0, 0.0, -2.0)));
    assert!(b.bodies[1].def.kinematic);
}

#[test]
fn load_total_is_split_equally_and_loads_on_one_node_add_up() {
    let text = format!(
        "{BASE}\n[[bodies.load]]\nselect = \"all\"\nforce = [0.0, 0.0, -42.0]\nramp = 1.0e-4\n\n[[bodies.load]]\nselect = \"z+\"\nmoment = [1.0, 0.0, 0.0]\nramp = 1.0e-4\n"
    );
    let b = build(&text);
    let s = &b.bodies[1];
    assert_eq!(s.def.loads.len(), s.node_count());
    let total: Vec3 = s.def.loads.iter().map(|l| l.force).sum();
    assert!((total - Vec3::new(0.0, 0.0, -42.0)).norm() < 1e-12);
    let m: Vec3 = s.def.loads.iter().map(|l| l.moment).sum();
    assert_eq!(m, Vec3::new(1.0, 0.0, 0.0));
    assert!(s.def.loads.iter().all(|l| l.t0 == 0.0 && l.t1 == 1.0e-4));
    assert_eq!(b.info[1].loaded_nodes, s.node_count());
}

#[test]
fn element_size_sets_cells_and_sphere_level() {
    let text =
        with("cells = [4, 4]", "element_size = 0.03").replace("level = 1", "element_size = 0.03");
    let b = build(&text);
    // ceil(0.4 / 0.03) = 14 cells per side
    assert_eq!(b.bodies[0].def.quads.len(), 14 * 14);
    // icosphere edge ~ 0.1 * 1.0515 / 2^l <= 0.03 first at l = 2: 320 triangles
    assert_eq!(b.bodies[1].def.tris.len(), 320);
}

#[test]
fn sphere_mass_approaches_the_shell_formula() {
    let b = build(&BASE.replace("level = 1", "level = 4"));
    let exact = 4.0 * std::f64::consts::PI * 0.1 * 0.1 * 1.0e-3 * 7800.0;
    let m = b.bodies[1].total_mass();
    assert!((m - exact).abs() / exact < 0.01, "{m} vs {exact}");
}

#[test]
fn cylinder_and_box_shapes_have_the_expected_counts_and_areas() {
    let text = with(
        "plate = { size = [0.4, 0.4], cells = [4, 4] }",
        "cylinder = { radius = 0.05, length = 0.3, cells = [24, 6] }\nposition = [0.0, 0.0, -0.5]",
    )
    .replace(
        "sphere = { radius = 0.1, level = 1 }",
        "box = { size = [0.2, 0.1, 0.1], cells = 4 }\nelement = \"tri\"",
    );
    let b = build(&text);
    assert_eq!(b.bodies[0].def.quads.len(), 24 * 6);
    // box: 4 x 2 x 2 cells, 2 triangles each
    assert_eq!(b.bodies[1].def.tris.len(), 2 * 2 * (4 * 2 + 2 * 2 + 2 * 4));
    let area = b.bodies[1].total_mass() / (7800.0 * 1.0e-3);
    assert!((area - 2.0 * (0.02 + 0.01 + 0.02)).abs() < 1e-12, "{area}");
}

#[test]
fn derived_margin_follows_the_documented_rule() {
    // two 4 x 4 quad plates of 0.1 m cells, one moving at 5 m/s: L_e = A / diagonal
    let text = r#"end_time = 1.0e-3
gravity = [0.0, 0.0, -10.0]
[materials.steel]
density = 7800.0
young = 200.0e9
poisson = 0.3
[[bodies]]
name = "a"
material = "steel"
thickness = 0.01
plate = { size = [0.4, 0.4], cells = [4, 4] }
[[bodies]]
name = "b"
material = "steel"
thickness = 0.01
plate = { size = [0.4, 0.4], cells = [4, 4] }
position = [0.0, 0.0, 0.1]
velocity = [0.0, 0.0, -5.0]
"#;
    let b = build(text);
    let le = 0.1 * 0.1 / (0.1 * 2f64.sqrt());
    let c = (200.0e9f64 / (7800.0 * (1.0 - 0.09))).sqrt();
    let dt = 0.9 * crash_core::forces::DT_SHAPE * le / c;
    let v = 5.0 + 10.0 * 1.0e-3;
    let expect = MARGIN_ELEMENT_FRACTION * le + 2.0 * v * dt * MARGIN_STEPS;
    assert!(
        (b.contact.margin - expect).abs() < 1e-12 * expect,
        "{} vs {expect}",
        b.contact.margin
    );
}

#[test]
fn summary_totals_match_the_bodies() {
    let b = build(BASE);
    let s = b.summary();
    assert_eq!(
        s.nodes,
        b.bodies.iter().map(|x| x.node_count()).sum::<usize>()
    );
    assert_eq!(s.elements, 16 + 80);
    assert_eq!(s.bodies[0].fixed_nodes, 5);
    // plate quads of 0.1 m: L = A / diagonal = 0.1 / sqrt 2; dt = DT_SHAPE L / c
    let c = (200.0e9f64 / (7800.0 * 0.91)).sqrt();
    let expect = crash_core::forces::DT_SHAPE * 0.1 / 2f64.sqrt() / c;
    assert!((s.bodies[0].dt_estimate - expect).abs() < 1e-15);
    let shown = s.to_string();
    assert!(
        shown.contains("plate") && shown.contains("ball") && shown.contains("96 elements"),
        "{shown}"
    );
}

#[test]
fn core_critical_dt_equals_the_summary_estimate() {
    let b = build(BASE);
    let (dt, body, _element) = b.critical_dt().expect("force pass");
    let s = b.summary();
    let (est, id) = s
        .bodies
        .iter()
        .map(|x| (x.dt_estimate, x.id))
        .fold((f64::INFINITY, 0), |a, x| if x.0 < a.0 { x } else { a });
    assert_eq!(body, id);
    assert!(
        (dt - est).abs() < 1e-12 * est,
        "core {dt} vs estimate {est}"
    );
    assert!((s.dt_estimate - 0.9 * dt).abs() < 1e-12 * dt);
}
