//! Pressure from a keyword deck (*LOAD_SHELL_SET over *SET_SHELL_LIST(_GENERATE),
//! *LOAD_SHELL_ELEMENT): over a whole part the same nodal loads, bit for bit, as a
//! scene's `[[bodies.pressure]]` on the same mesh; over some shells a converted scene
//! (`elements = [..]`) with the same hash; on a free plate the impulse p A x the
//! curve's integral (momentum balance).

mod common;

use common::temp_dir;
use crash_core::{Body, Clock, Group, Vec3};
use crash_scene::keyword::{self, DeckOptions};
use crash_scene::Built;
use std::path::{Path, PathBuf};

/// A power of two: step times are exact, curve points at multiples of H fall on steps.
const H: f64 = 1.0 / 4_194_304.0;
const NX: usize = 8;
const NY: usize = 4;
/// Plate size [m].
const LX: f64 = 0.4;
const LY: f64 = 0.2;
const P: f64 = 2.5e3;

/// A free NX x NY plate of quads in z = 0 (normals +z); `loads` appended as cards.
fn deck(loads: &str) -> String {
    let mut s = String::from("*KEYWORD\n*CONTROL_TERMINATION\n    1.0e-3\n*NODE\n");
    let id = |i: usize, j: usize| 1 + j * (NX + 1) + i;
    for j in 0..=NY {
        for i in 0..=NX {
            let (x, y) = (LX * i as f64 / NX as f64, LY * j as f64 / NY as f64);
            s += &format!("{},{x:e},{y:e},0.0\n", id(i, j));
        }
    }
    s += "*ELEMENT_SHELL\n";
    for j in 0..NY {
        for i in 0..NX {
            let e = 1 + j * NX + i;
            s += &format!(
                "{e},1,{},{},{},{}\n",
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            );
        }
    }
    s += "*PART\nplate\n1,1,1\n*SECTION_SHELL\n1\n2.0e-3\n";
    s += "*MAT_ELASTIC\n1,7800.0,2.0e11,0.3\n";
    // a triangular pulse over 60 steps: integral 30 H
    s += &format!(
        "*DEFINE_CURVE\n1\n0.0,0.0\n{:e},1.0\n{:e},0.0\n",
        20.0 * H,
        60.0 * H
    );
    s += loads;
    s += "*END\n";
    s
}

fn write(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("plate.k");
    std::fs::write(&p, text).expect("write deck");
    p
}

fn build_deck(path: &Path) -> Built {
    crash_scene::load_input(path, &DeckOptions::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
}

fn convert(deck: &Path, scene: &Path) -> String {
    keyword::convert(deck, &DeckOptions::default(), "plate")
        .expect("converts")
        .write(scene)
        .expect("writes");
    std::fs::read_to_string(scene).expect("read scene")
}

fn build_scene(path: &Path) -> Built {
    crash_scene::load(path)
        .and_then(|s| s.build())
        .unwrap_or_else(|e| panic!("{e}"))
}

fn same_loads(a: &Body, b: &Body) {
    assert_eq!(a.def.loads, b.def.loads);
    assert_eq!(a.def.load_of, b.def.load_of);
    assert_eq!(a.def.curves, b.def.curves);
}

/// Elements 1..NX/2 of each row (the left half) by generated ranges.
fn left_half() -> String {
    let mut s = String::from("*SET_SHELL_LIST_GENERATE\n7\n");
    for j in 0..NY {
        let first = 1 + j * NX;
        s += &format!("{first},{},", first + NX / 2 - 1);
    }
    s.pop();
    s + "\n"
}

#[test]
fn load_shell_set_over_a_whole_part_gives_the_scene_pressures_loads_bit_for_bit() {
    let dir = temp_dir("deck-pressure-all");
    let all = format!(
        "*SET_SHELL_LIST_GENERATE\n7\n1,{}\n*LOAD_SHELL_SET\n7,1,{P:e},0.0\n",
        NX * NY
    );
    let from_deck = build_deck(&write(&dir, &deck(&all)));
    // the same plate without the deck's pressure, the pressure written as a scene's
    let bare = write(&dir, &deck(""));
    let scene = dir.join("plate.toml");
    let mut text = convert(&bare, &scene);
    text += &format!("\n[[bodies.pressure]]\nvalue = {P:e}\ncurve = \"lc1\"\n");
    std::fs::write(&scene, text).expect("write scene");
    let from_toml = build_scene(&scene);
    assert!(!from_deck.bodies[0].def.loads.is_empty());
    same_loads(&from_deck.bodies[0], &from_toml.bodies[0]);
}

#[test]
fn load_shell_on_some_shells_converts_to_a_scene_with_the_same_hash_and_loads() {
    let dir = temp_dir("deck-pressure-some");
    let loads = format!(
        "{}*LOAD_SHELL_SET\n7,1,{P:e}\n*LOAD_SHELL_ELEMENT\n{},1,{P:e}\n",
        left_half(),
        NX
    );
    let d = write(&dir, &deck(&loads));
    let from_deck = build_deck(&d);
    let scene = dir.join("plate.toml");
    let text = convert(&d, &scene);
    assert!(text.contains("elements = ["), "{text}");
    let from_toml = build_scene(&scene);
    same_loads(&from_deck.bodies[0], &from_toml.bodies[0]);
    assert_eq!(from_deck.scene_hash, from_toml.scene_hash);
}

#[test]
fn deck_pressure_on_a_free_plate_gives_impulse_p_area_times_curve_integral() {
    let dir = temp_dir("deck-pressure-impulse");
    // the left half by a set, and element NX (the first row's last) on its own
    let loads = format!(
        "{}*LOAD_SHELL_SET\n7,1,{P:e}\n*LOAD_SHELL_ELEMENT\n{},1,{P:e}\n",
        left_half(),
        NX
    );
    let b = build_deck(&write(&dir, &deck(&loads)));
    let mut g = Group::new(b.bodies, Vec3::zeros());
    g.start().expect("start");
    let mut clock = Clock::default();
    for _ in 0..80 {
        g.advance(&clock, H).expect("step");
        clock = clock.after(H);
    }
    let area = LX * LY / 2.0 + (LX / NX as f64) * (LY / NY as f64);
    // the curve is back to 0 at 60 H: the momentum is the whole impulse, along -n = -z
    let expected = Vec3::new(0.0, 0.0, -P * area * 30.0 * H);
    let mom = g.bodies[0].linear_momentum();
    let err = (mom - expected).norm() / expected.norm();
    // tolerance: round-off of summing the nodal loads over 80 steps
    assert!(
        err < 1e-9,
        "momentum {mom:?}, impulse p A int(curve) = {expected:?}, rel {err:e}"
    );
}

#[test]
fn arrival_time_and_unknown_shells_stop_at_their_card() {
    let dir = temp_dir("deck-pressure-errors");
    for (loads, line, what) in [
        (
            format!("*LOAD_SHELL_ELEMENT\n3,1,{P:e},1.0e-5\n"),
            "*LOAD_SHELL_ELEMENT",
            "arrival time",
        ),
        (
            format!("*LOAD_SHELL_SET\n9,1,{P:e}\n"),
            "*LOAD_SHELL_SET",
            "shell set 9 is not defined",
        ),
        (
            format!("*LOAD_SHELL_ELEMENT\n999,1,{P:e}\n"),
            "*LOAD_SHELL_ELEMENT",
            "element 999 is not defined",
        ),
    ] {
        let text = deck(&loads);
        let n = text.lines().position(|l| l == line).expect("keyword line") + 2;
        let p = write(&dir, &text);
        let e = crash_scene::load_input(&p, &DeckOptions::default())
            .map(|_| ())
            .expect_err("refused")
            .to_string();
        assert!(
            e.contains(&format!("plate.k:{n}")) && e.contains(line) && e.contains(what),
            "{e}"
        );
    }
}

#[test]
fn scene_pressure_on_an_element_the_mesh_lacks_is_refused_at_its_key() {
    let dir = temp_dir("scene-pressure-elements");
    let scene = dir.join("plate.toml");
    let mut text = convert(&write(&dir, &deck("")), &scene);
    text += "\n[[bodies.pressure]]\nvalue = 1.0\nelements = [3, 77]\n";
    std::fs::write(&scene, text).expect("write scene");
    let e = crash_scene::load(&scene)
        .and_then(|s| s.build())
        .map(|_| ())
        .expect_err("refused")
        .to_string();
    assert!(
        e.contains("bodies[0].pressure[0].elements") && e.contains("no element 77"),
        "{e}"
    );
}
