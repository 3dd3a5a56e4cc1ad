//! Prescribed displacement from a deck (*BOUNDARY_PRESCRIBED_MOTION_SET, VAD = 2):
//! the nodes are at x0 + SF d(t_n) at every step, `crash convert` writes it as
//! `displacement = [..]` with the same scene hash, and a scene refuses a displacement
//! whose curve does not start at 0.

mod common;

use common::temp_dir;
use crash_core::{Clock, Group, Vec3};
use crash_scene::keyword::{self, DeckOptions};
use std::path::{Path, PathBuf};

const H: f64 = 1.0 / 4_194_304.0;
const N: usize = 4;

/// A free N x N plate of 0.2 m, its x = 0 edge (set 1) driven along z by curve 1 with
/// VAD = 2 (SF = 1e-4 m), its other DOFs held.
fn deck() -> String {
    let mut s = String::from("*KEYWORD\n*CONTROL_TERMINATION\n    1.0e-3\n*NODE\n");
    let id = |i: usize, j: usize| 1 + j * (N + 1) + i;
    for j in 0..=N {
        for i in 0..=N {
            let (x, y) = (0.2 * i as f64 / N as f64, 0.2 * j as f64 / N as f64);
            s += &format!("{},{x:e},{y:e},0.0\n", id(i, j));
        }
    }
    s += "*ELEMENT_SHELL\n";
    for j in 0..N {
        for i in 0..N {
            s += &format!(
                "{},1,{},{},{},{}\n",
                1 + j * N + i,
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            );
        }
    }
    s += "*PART\nplate\n1,1,1\n*SECTION_SHELL\n1\n2.0e-3\n";
    s += "*MAT_ELASTIC\n1,7800.0,2.0e11,0.3\n";
    s += "*SET_NODE_LIST\n1\n";
    s += &(0..=N)
        .map(|j| id(0, j).to_string())
        .collect::<Vec<_>>()
        .join(",");
    s += "\n*BOUNDARY_SPC_SET\n1,0,1,1,0,1,1,1\n";
    s += &format!(
        "*DEFINE_CURVE\n1\n0.0,0.0\n{:e},1.0\n{:e},0.25\n",
        20.0 * H,
        50.3 * H
    );
    s += "*BOUNDARY_PRESCRIBED_MOTION_SET\n1,3,2,1,1.0e-4\n";
    s += "*END\n";
    s
}

fn write(dir: &Path) -> PathBuf {
    let p = dir.join("plate.k");
    std::fs::write(&p, deck()).expect("write deck");
    p
}

fn curve(t: f64) -> f64 {
    let pts = [(0.0, 0.0), (20.0 * H, 1.0), (50.3 * H, 0.25)];
    crash_core::TimeCurve {
        points: pts.to_vec(),
    }
    .value(t)
}

#[test]
fn deck_prescribed_displacement_puts_the_nodes_at_sf_times_the_curve_every_step() {
    let dir = temp_dir("deck-displacement");
    let b = crash_scene::load_input(&write(&dir), &DeckOptions::default())
        .and_then(|s| Ok(s.build()?))
        .unwrap_or_else(|e| panic!("{e}"));
    let body = &b.bodies[0];
    assert!(body.def.programs.iter().all(|p| p.displacement));
    let edge: Vec<usize> = (0..body.node_count())
        .filter(|&n| body.def.x0[n].x == 0.0)
        .collect();
    assert_eq!(edge.len(), N + 1);
    let mut g = Group::new(b.bodies, Vec3::zeros());
    g.start().expect("start");
    let mut clock = Clock::default();
    for _ in 0..80 {
        g.advance(&clock, H).expect("step");
        clock = clock.after(H);
        let b = &g.bodies[0];
        let want = Vec3::new(0.0, 0.0, 1e-4 * curve(clock.time));
        for &n in &edge {
            let u = b.state.x[n] - b.def.x0[n];
            // round-off of the increments added to coordinates up to 0.2 m
            assert!(
                (u - want).norm() <= 1e-12 * b.def.x0[n].norm().max(1e-4),
                "t {}: node {n} moved {u:?}, want {want:?}",
                clock.time
            );
        }
    }
}

#[test]
fn converted_displacement_scene_has_the_same_hash() {
    let dir = temp_dir("deck-displacement-convert");
    let d = write(&dir);
    let from_deck = crash_scene::load_input(&d, &DeckOptions::default())
        .and_then(|s| Ok(s.build()?))
        .unwrap_or_else(|e| panic!("{e}"));
    let scene = dir.join("plate.toml");
    keyword::convert(&d, &DeckOptions::default(), "plate")
        .expect("converts")
        .write(&scene)
        .expect("writes");
    let text = std::fs::read_to_string(&scene).expect("scene");
    assert!(text.contains("displacement = [0.0, 0.0, 0.0001]"), "{text}");
    let from_toml = crash_scene::load(&scene)
        .and_then(|s| s.build())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(from_deck.scene_hash, from_toml.scene_hash);
    assert_eq!(
        from_deck.bodies[0].def.programs,
        from_toml.bodies[0].def.programs
    );
    // a displacement curve that does not start at 0 would jump the nodes: refused
    let bad = text.replace("points = [[0.0, 0.0]", "points = [[0.0, 0.5]");
    assert_ne!(bad, text);
    std::fs::write(&scene, bad).expect("write");
    let e = crash_scene::load(&scene)
        .and_then(|s| s.build())
        .map(|_| ())
        .expect_err("refused")
        .to_string();
    assert!(
        e.contains("prescribe[0].curve") && e.contains("0 at t = 0"),
        "{e}"
    );
}
