//! LS-DYNA keyword decks written for these tests (tests/data/keyword): the same model
//! in fixed columns (with an include and one long-format keyword), in the comma format
//! and in the long format builds the same bodies; the bodies are what the deck says;
//! `crash convert`'s scene and meshes rebuild them exactly; a generated deck of a few
//! thousand shells converts and runs.

mod common;

use common::temp_dir;
use crash_core::body::{dof, NO_PROGRAM};
use crash_core::{Body, Group, Run, Vec3};
use crash_scene::keyword::{self, DeckOptions};
use crash_scene::Built;
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/keyword")
        .join(name)
}

fn build_deck(path: &Path) -> Built {
    crash_scene::load_input(path, &DeckOptions::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Everything of two bodies that the scene decides (state, constraints, programs,
/// loads, section, elements).
fn same_body(a: &Body, b: &Body) {
    assert_eq!(a.def.name, b.def.name);
    assert_eq!(a.state.x, b.state.x, "{}", a.def.name);
    assert_eq!(a.state.v, b.state.v, "{}", a.def.name);
    assert_eq!(a.state.w, b.state.w, "{}", a.def.name);
    assert_eq!(a.def.mass, b.def.mass, "{}", a.def.name);
    assert_eq!(a.def.inertia, b.def.inertia, "{}", a.def.name);
    assert_eq!(a.def.fixed, b.def.fixed, "{}", a.def.name);
    assert_eq!(a.def.program, b.def.program, "{}", a.def.name);
    assert_eq!(a.def.programs, b.def.programs, "{}", a.def.name);
    assert_eq!(a.def.loads, b.def.loads, "{}", a.def.name);
    assert_eq!(a.def.section, b.def.section, "{}", a.def.name);
    assert_eq!(
        a.def.tris.iter().map(|e| e.nodes).collect::<Vec<_>>(),
        b.def.tris.iter().map(|e| e.nodes).collect::<Vec<_>>()
    );
    assert_eq!(
        a.def.quads.iter().map(|e| e.nodes).collect::<Vec<_>>(),
        b.def.quads.iter().map(|e| e.nodes).collect::<Vec<_>>()
    );
    assert_eq!(
        (a.def.contact, a.def.self_contact, a.def.kinematic),
        (b.def.contact, b.def.self_contact, b.def.kinematic)
    );
}

fn same_built(a: &Built, b: &Built) {
    assert_eq!(a.bodies.len(), b.bodies.len());
    for (x, y) in a.bodies.iter().zip(&b.bodies) {
        same_body(x, y);
    }
    assert_eq!(
        (a.end_time, a.safety, a.output_interval),
        (b.end_time, b.safety, b.output_interval)
    );
    assert_eq!(a.contact, b.contact);
    assert_eq!(a.outputs, b.outputs);
}

#[test]
fn fixed_comma_and_long_formats_give_the_same_bodies() {
    let fixed = build_deck(&data("impact.k"));
    for other in ["impact-free.k", "impact-long.k"] {
        same_built(&fixed, &build_deck(&data(other)));
    }
}

#[test]
fn impact_deck_builds_what_the_deck_says() {
    let b = build_deck(&data("impact.k"));
    assert_eq!(b.name, "impact");
    assert!(b.notes.is_empty(), "{:?}", b.notes);
    assert_eq!(
        (b.end_time, b.safety, b.output_interval),
        (1.0e-4, 0.8, 1.0e-5)
    );
    let (plate, imp) = (&b.bodies[0], &b.bodies[1]);
    assert_eq!(
        (plate.def.name.as_str(), imp.def.name.as_str()),
        ("plate", "impactor")
    );
    // 4 x 4 quads; the impactor: 3 quads, a 4-node card with N3 = N4 and a 3-node card
    assert_eq!(
        (
            plate.node_count(),
            plate.def.tris.len(),
            plate.def.quads.len()
        ),
        (25, 0, 16)
    );
    assert_eq!(
        (imp.node_count(), imp.def.tris.len(), imp.def.quads.len()),
        (9, 2, 3)
    );
    // steel, 2 mm; SHRF 0.8333 on the plate, 5/6 (crash's default) on the impactor
    let g = 2.0e11 / (2.0 * 1.3);
    assert!((plate.def.section.shear - 0.8333 * g * 0.002).abs() < 1e-6 * plate.def.section.shear);
    assert!((plate.total_mass() - 7800.0 * 0.002 * 0.04).abs() < 1e-12);
    // the x- edge (node set 1) held in all DOFs, node 5 in z by its TC = 3
    let held: Vec<(usize, u8)> = (0..25)
        .filter(|&i| plate.def.fixed[i] != 0)
        .map(|i| (i, plate.def.fixed[i]))
        .collect();
    assert_eq!(
        held,
        vec![
            (0, dof::ALL),
            (4, dof::Z),
            (5, dof::ALL),
            (10, dof::ALL),
            (15, dof::ALL),
            (20, dof::ALL)
        ]
    );
    // the rigid impactor (CON1 = 4: x, y; CON2 = 7) prescribed in z: kinematic, moving
    // down at 2 m/s after a 10 us ramp (curve 1 is a ramp, SF = -2)
    assert!(imp.def.kinematic);
    assert!(imp.def.program.iter().all(|&p| p == 0));
    assert_eq!(imp.def.programs.len(), 1);
    assert_eq!(imp.def.programs[0].velocity, Vec3::new(0.0, 0.0, -2.0));
    assert_eq!(imp.def.programs[0].ramp, 1.0e-5);
    // -10 N on node 13 (index 12), a constant curve: a step at t = 0
    assert_eq!(plate.def.loads.len(), 1);
    let l = plate.def.loads[0];
    assert_eq!(
        (l.node, l.force, l.t0, l.t1),
        (12, Vec3::new(0.0, 0.0, -10.0), 0.0, 0.0)
    );
    assert!(
        plate.def.contact && imp.def.contact && !plate.def.self_contact && !imp.def.self_contact
    );
    let o = &b.outputs;
    assert_eq!(
        [o.glstat, o.matsum, o.rcforc, o.nodout, o.spcforc],
        [Some(1.0e-6); 5]
    );
    // history nodes 13 (plate, index 12) and 105 (impactor, index 4)
    assert_eq!(o.history, vec![(0, 12, 13), (1, 4, 105)]);
}

#[test]
fn converted_scene_and_meshes_rebuild_the_same_bodies() {
    let deck = data("impact.k");
    let dir = temp_dir("convert-impact");
    let scene = dir.join("impact.toml");
    let c = keyword::convert(&deck, &DeckOptions::default(), "impact").expect("converts");
    let written = c.write(&scene).expect("writes");
    assert_eq!(
        written,
        vec![
            scene.clone(),
            dir.join("impact.part1.msh"),
            dir.join("impact.part2.msh")
        ]
    );
    let from_toml = crash_scene::load(&scene)
        .and_then(|s| s.build())
        .unwrap_or_else(|e| panic!("{e}"));
    let from_deck = build_deck(&deck);
    same_built(&from_deck, &from_toml);
    // the deck's in-memory meshes hash as the files written
    assert_eq!(from_deck.scene_hash, from_toml.scene_hash);
}

#[test]
fn impact_deck_runs_with_the_edge_held_and_the_impactor_driven() {
    let b = build_deck(&data("impact.k"));
    let mut run = Run::new(Group::new(b.bodies.clone(), b.gravity), b.run_config()).expect("start");
    while run.time() < 2.0e-5 {
        run.step().expect("step");
    }
    let (plate, imp) = (&run.group.bodies[0], &run.group.bodies[1]);
    for i in [0, 5, 10, 15, 20] {
        assert_eq!(plate.state.x[i], plate.def.x0[i]);
    }
    // after the ramp every impactor node moves at (0, 0, -2) (the half-step velocity)
    for v in &imp.state.v {
        assert_eq!(*v, Vec3::new(0.0, 0.0, -2.0));
    }
    assert!(imp.state.x[0].z < imp.def.x0[0].z);
    assert!(plate.def.program.iter().all(|&p| p == NO_PROGRAM));
}

/// A plate of n x n quads held on its edges, a smaller elastic plate above it thrown
/// down with a spin (*INITIAL_VELOCITY_GENERATION), a ramped nodal load on the plate's
/// centre, contact between the two.
fn big_deck(n: usize, m: usize) -> String {
    let mut s = String::from("*KEYWORD\n*TITLE\ngenerated plate and thrown tile\n");
    s += "*CONTROL_TERMINATION\n    2.0e-4\n*DATABASE_BINARY_D3PLOT\n    2.0e-5\n*NODE\n";
    let h = 0.6 / n as f64;
    let id = |i: usize, j: usize| 1 + j * (n + 1) + i;
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (-0.3 + h * i as f64, -0.3 + h * j as f64);
            s += &format!("{:8}{:16.8}{:16.8}{:16.8}\n", id(i, j), x, y, 0.0);
        }
    }
    let base = 100_000;
    let tid = |i: usize, j: usize| base + 1 + j * (m + 1) + i;
    for j in 0..=m {
        for i in 0..=m {
            let (x, y) = (
                -0.05 + 0.1 * i as f64 / m as f64,
                -0.05 + 0.1 * j as f64 / m as f64,
            );
            s += &format!("{:8}{:16.8}{:16.8}{:16.8}\n", tid(i, j), x, y, 0.02);
        }
    }
    s += "*ELEMENT_SHELL\n";
    for j in 0..n {
        for i in 0..n {
            let e = 1 + j * n + i;
            s += &format!(
                "{e:8}{:8}{:8}{:8}{:8}{:8}\n",
                1,
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            );
        }
    }
    for j in 0..m {
        for i in 0..m {
            let e = base + 1 + j * m + i;
            s += &format!(
                "{e:8}{:8}{:8}{:8}{:8}{:8}\n",
                2,
                tid(i, j),
                tid(i + 1, j),
                tid(i + 1, j + 1),
                tid(i, j + 1)
            );
        }
    }
    s += "*PART\nplate\n         1         1         1\ntile\n         2         1         1\n";
    s += "*SECTION_SHELL\n         1\n     0.002\n";
    s += "*MAT_ELASTIC\n         1    2700.0    7.0e10      0.33\n";
    // the plate's edges by generated ranges: bottom and top rows, and the side columns
    s += "*SET_NODE_LIST_GENERATE\n         1\n";
    s += &format!(
        "{:10}{:10}{:10}{:10}\n",
        id(0, 0),
        id(n, 0),
        id(0, n),
        id(n, n)
    );
    s += "*SET_NODE_LIST\n         2\n";
    let sides: Vec<usize> = (1..n).flat_map(|j| [id(0, j), id(n, j)]).collect();
    for chunk in sides.chunks(8) {
        s += &chunk.iter().map(|k| format!("{k:10}")).collect::<String>();
        s += "\n";
    }
    s += "*BOUNDARY_SPC_SET\n         1         0         1         1         1         1         1         1\n";
    s += "         2         0         1         1         1         1         1         1\n";
    s += "*SET_PART_LIST\n         7\n         2\n";
    s += "*INITIAL_VELOCITY_GENERATION\n";
    s += "         7         1     100.0       0.0       0.0      -5.0\n";
    s += "       0.0       0.0      0.02       0.0       0.0       1.0\n";
    s += "*DEFINE_CURVE\n         3\n                 0.0                 0.0\n              5.0e-5                 1.0\n";
    s += &format!(
        "*LOAD_NODE_POINT\n{:10}         3         3     -50.0\n",
        id(n / 2, n / 2)
    );
    s += "*CONTACT_AUTOMATIC_SURFACE_TO_SURFACE_ID\n         1 tile on plate\n         2         1         3         3\n";
    s += "*END\n";
    s
}

#[test]
fn generated_deck_of_thousands_of_shells_converts_and_runs() {
    let (n, m) = (60, 10);
    let dir = temp_dir("big-deck");
    let deck = dir.join("big.k");
    std::fs::write(&deck, big_deck(n, m)).expect("write deck");
    let b = build_deck(&deck);
    let (plate, tile) = (&b.bodies[0], &b.bodies[1]);
    assert_eq!(plate.def.quads.len() + tile.def.quads.len(), n * n + m * m);
    assert_eq!(plate.node_count(), (n + 1) * (n + 1));
    // every edge node held: 4 n of them
    assert_eq!(
        plate.def.fixed.iter().filter(|&&f| f == dof::ALL).count(),
        4 * n
    );
    // the tile spins at 100 rad/s about the z axis through (0, 0, 0.02): v = V + w x r
    for (x, v) in tile.state.x.iter().zip(&tile.state.v) {
        let expect = Vec3::new(0.0, 0.0, -5.0)
            + Vec3::new(0.0, 0.0, 100.0).cross(&(x - Vec3::new(0.0, 0.0, 0.02)));
        assert!((v - expect).norm() < 1e-12, "{v} vs {expect}");
    }
    // the load ramps over 50 us (curve 3: 0 at 0, 1 at 5e-5, then held)
    assert_eq!(plate.def.loads.len(), 1);
    assert_eq!(
        (plate.def.loads[0].t0, plate.def.loads[0].t1),
        (0.0, 5.0e-5)
    );
    assert_eq!(plate.def.loads[0].force, Vec3::new(0.0, 0.0, -50.0));
    // convert and rebuild: the same bodies
    let scene = dir.join("big.toml");
    keyword::convert(&deck, &DeckOptions::default(), "big")
        .expect("converts")
        .write(&scene)
        .expect("writes");
    let again = crash_scene::load(&scene)
        .and_then(|s| s.build())
        .unwrap_or_else(|e| panic!("{e}"));
    same_built(&b, &again);
    assert_eq!(b.scene_hash, again.scene_hash);
    // and it runs
    let mut run = Run::new(Group::new(b.bodies.clone(), b.gravity), b.run_config()).expect("start");
    for _ in 0..20 {
        run.step().expect("step");
    }
    assert!(run.time() > 0.0);
}
