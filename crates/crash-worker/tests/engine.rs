//! The worker's engine on its own: it integrates its groups exactly as the core does,
//! keeps every definition it received (a returning body travels as its state), and
//! refuses what cannot be right (a command for another moment, a state without a
//! definition, a frame of a body it does not hold).
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_core::hash::state_hash;
use crash_core::shapes::{icosphere, plate, ElementKind};
use crash_core::{Body, Clock, Group, Material, Section, Stabilization, Vec3};
use crash_link::{BodyLoad, Command, Reply, Setup};
use crash_worker::Engine;

fn bodies() -> Vec<Body> {
    let sec = Section::new(Material::steel(), 0.001);
    let mut p = Body::new(
        0,
        "plate",
        &plate(0.1, 0.1, 4, 4, ElementKind::Quad),
        sec,
        Stabilization::default(),
    )
    .unwrap();
    p.fix(0, crash_core::dof::ALL);
    let mut s = Body::new(
        1,
        "ball",
        &icosphere(0.02, 1),
        sec,
        Stabilization::default(),
    )
    .unwrap();
    s.set_rigid_velocity(
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(0.0, 5.0, 0.0),
        Vec3::zeros(),
    );
    vec![p, s]
}

fn setup() -> Setup {
    Setup {
        gravity: Vec3::new(0.0, 0.0, -9.81),
        contact: Default::default(),
        reactions: false,
        probes: Default::default(),
    }
}

fn ack(r: Reply) {
    assert!(matches!(r, Reply::Ack), "{r:?}");
}

fn error(r: Reply) -> String {
    match r {
        Reply::Error(e) => e,
        other => panic!("expected an error, got {other:?}"),
    }
}

/// An engine holding both bodies in one group, started.
fn started() -> Engine {
    let mut e = Engine::new();
    ack(e.handle(Command::Setup(setup())));
    ack(e.handle(Command::Load {
        at: Clock::default(),
        bodies: bodies().into_iter().map(BodyLoad::whole).collect(),
    }));
    ack(e.handle(Command::Regroup(vec![vec![0, 1]])));
    assert!(matches!(e.handle(Command::Start), Reply::Report(_)));
    e
}

#[test]
fn steps_give_the_core_groups_bits() {
    let mut e = started();
    let mut g = Group::new(bodies(), setup().gravity);
    g.start().unwrap();
    let mut clock = Clock::default();
    for _ in 0..20 {
        let Reply::Report(rep) = e.handle(Command::Step {
            at: clock,
            dt: 1e-7,
        }) else {
            panic!("no report")
        };
        let core = g.advance(&clock, 1e-7).unwrap();
        assert_eq!(rep.bodies, core);
        clock = clock.after(1e-7);
    }
    let Reply::States(states) = e.handle(Command::States(Vec::new())) else {
        panic!("no states")
    };
    let held: Vec<Body> = states
        .into_iter()
        .zip(bodies())
        .map(|((_, s), b)| Body::from_parts(b.def, s).unwrap())
        .collect();
    assert_eq!(state_hash(&held), state_hash(&g.bodies));
    assert_eq!(e.clock(), Some(clock));
}

#[test]
fn a_step_for_another_moment_is_refused() {
    let mut e = started();
    let wrong = Clock {
        step: 3,
        time: 3e-7,
        last_dt: 1e-7,
    };
    let msg = error(e.handle(Command::Step {
        at: wrong,
        dt: 1e-7,
    }));
    assert!(msg.contains("step 3") && msg.contains("step 0"), "{msg}");
    let msg = error(e.handle(Command::Step {
        at: Clock::default(),
        dt: f64::NAN,
    }));
    assert!(msg.contains("invalid time step"), "{msg}");
}

#[test]
fn a_body_that_leaves_and_returns_travels_as_its_state() {
    let mut e = started();
    let clock = Clock::default();
    let Reply::Unloaded(out) = e.handle(Command::Unload {
        ids: vec![1],
        with_def: vec![],
    }) else {
        panic!("not unloaded")
    };
    assert_eq!(out.len(), 1);
    assert!(out[0].def.is_none(), "the definition was not asked for");
    assert!(e.has_definition(1), "the definition is kept");
    ack(e.handle(Command::Regroup(vec![vec![0]])));
    ack(e.handle(Command::Load {
        at: clock,
        bodies: out,
    }));
    ack(e.handle(Command::Regroup(vec![vec![0], vec![1]])));
    assert_eq!(e.layout(), vec![vec![0], vec![1]]);
    // another engine never saw body 1: a bare state is refused
    let mut other = Engine::new();
    ack(other.handle(Command::Setup(setup())));
    let Reply::Unloaded(bare) = e.handle(Command::Unload {
        ids: vec![1],
        with_def: vec![],
    }) else {
        panic!("not unloaded")
    };
    let msg = error(other.handle(Command::Load {
        at: clock,
        bodies: bare,
    }));
    assert!(msg.contains("without a definition"), "{msg}");
}

#[test]
fn frames_and_unloads_of_bodies_not_held_are_refused() {
    let mut e = started();
    let Reply::Frame(f) = e.handle(Command::Frame(vec![1, 0])) else {
        panic!("no frame")
    };
    assert_eq!(f.iter().map(|b| b.id).collect::<Vec<_>>(), vec![1, 0]);
    let msg = error(e.handle(Command::Frame(vec![7])));
    assert!(msg.contains("body 7"), "{msg}");
    let msg = error(e.handle(Command::Unload {
        ids: vec![9],
        with_def: vec![],
    }));
    assert!(msg.contains("body 9"), "{msg}");
    let msg = error(e.handle(Command::Regroup(vec![vec![0, 0, 1]])));
    assert!(msg.contains("twice"), "{msg}");
}
