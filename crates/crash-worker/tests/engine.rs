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
    ack(e.handle(Command::regroup(vec![vec![0, 1]])));
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
            kin_nodes: false,
            due: crash_core::Due::ALL,
            contact: Default::default(),
            direct: false,
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
        kin_nodes: false,
        due: crash_core::Due::ALL,
        contact: Default::default(),
        direct: false,
    }));
    assert!(msg.contains("step 3") && msg.contains("step 0"), "{msg}");
    let msg = error(e.handle(Command::Step {
        at: Clock::default(),
        dt: f64::NAN,
        kin_nodes: false,
        due: crash_core::Due::ALL,
        contact: Default::default(),
        direct: false,
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
    ack(e.handle(Command::regroup(vec![vec![0]])));
    ack(e.handle(Command::Load {
        at: clock,
        bodies: out,
    }));
    ack(e.handle(Command::regroup(vec![vec![0], vec![1]])));
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
    let msg = error(e.handle(Command::regroup(vec![vec![0, 0, 1]])));
    assert!(msg.contains("twice"), "{msg}");
}

/// A kinematic plate (every node prescribed: up at 1 m/s) and two balls falling onto
/// it at either end, so that both press on it within a few hundred steps.
fn kinematic_scene() -> Vec<Body> {
    let sec = Section::new(Material::steel(), 0.001);
    let mut p = Body::new(
        0,
        "plate",
        &plate(0.2, 0.1, 8, 4, ElementKind::Quad),
        sec,
        Stabilization::default(),
    )
    .unwrap();
    let all: Vec<usize> = (0..p.node_count()).collect();
    p.prescribe(
        &all,
        crash_core::VelocityProgram::ramped(Vec3::new(0.0, 0.0, 1.0), Vec3::zeros(), 0.0),
    );
    assert!(p.def.kinematic);
    p.def_mut().contact = true;
    let ball = |id: u32, x: f64| {
        let mut mesh = icosphere(0.02, 1);
        // lowest node 1.2 mm above the plate's mid-surface: 0.2 mm from contact
        let low = mesh.nodes.iter().map(|n| n.z).fold(f64::INFINITY, f64::min);
        for n in &mut mesh.nodes {
            *n += Vec3::new(x, 0.0, 0.0012 - low);
        }
        let mut s = Body::new(id, "ball", &mesh, sec, Stabilization::default()).unwrap();
        s.def_mut().contact = true;
        s.set_rigid_velocity(Vec3::new(0.0, 0.0, -2.0), Vec3::zeros(), Vec3::zeros());
        s
    };
    vec![p, ball(1, -0.06), ball(2, 0.06)]
}

fn motion_bits(b: &Body) -> Vec<u64> {
    let s = &b.state;
    s.x.iter()
        .chain(&s.v)
        .chain(&s.w)
        .flat_map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

/// Read-only copies of a kinematic body, in groups on the owner's worker (made there)
/// and on another worker (lent by the owner), stay bit-identical to the owner through
/// contact: contact forces on a copy never flow back into its motion. The balls move
/// exactly as in one group with the plate (the core driver's arrangement).
#[test]
fn kinematic_copies_stay_bit_identical_to_the_owner() {
    let [p, b1, b2]: [Body; 3] = kinematic_scene().try_into().unwrap();
    let at = Clock::default();
    // worker A: the plate's owner, ball 1 with a copy; worker B: ball 2 with a copy
    let mut a = Engine::new();
    let mut b = Engine::new();
    for e in [&mut a, &mut b] {
        ack(e.handle(Command::Setup(setup())));
    }
    ack(a.handle(Command::Load {
        at,
        bodies: vec![BodyLoad::whole(p.clone()), BodyLoad::whole(b1.clone())],
    }));
    let Reply::Unloaded(lent) = a.handle(Command::Lend {
        ids: vec![0],
        with_def: vec![0],
    }) else {
        panic!("no lend")
    };
    ack(b.handle(Command::LoadCopies { at, bodies: lent }));
    ack(b.handle(Command::Load {
        at,
        bodies: vec![BodyLoad::whole(b2.clone())],
    }));
    ack(a.handle(Command::Regroup {
        groups: vec![vec![0], vec![1]],
        copies: vec![vec![], vec![0]],
    }));
    ack(b.handle(Command::Regroup {
        groups: vec![vec![2]],
        copies: vec![vec![0]],
    }));
    assert_eq!(a.copies(), vec![vec![], vec![0]]);
    assert_eq!(b.layout(), vec![vec![2]]);
    // the reference: all three in one group
    let mut one = Group::new(vec![p, b1, b2], setup().gravity);
    one.contact = setup().contact;
    one.start().unwrap();
    for (e, ids) in [(&mut a, vec![0, 1]), (&mut b, vec![2])] {
        let Reply::Report(r) = e.handle(Command::Start) else {
            panic!("no start report")
        };
        // a copy is never reported: only its owner reports the plate
        assert_eq!(r.bodies.iter().map(|x| x.id).collect::<Vec<_>>(), ids);
    }
    let mut clock = Clock::default();
    let (mut touched, dt) = (0, 5.0e-7);
    for _ in 0..800 {
        let mut stats = Vec::new();
        for e in [&mut a, &mut b] {
            let Reply::Report(r) = e.handle(Command::Step {
                at: clock,
                dt,
                kin_nodes: true,
                due: crash_core::Due::ALL,
                contact: Default::default(),
                direct: false,
            }) else {
                panic!("no step report")
            };
            stats.extend(r.contacts);
        }
        one.advance(&clock, dt).unwrap();
        clock = clock.after(dt);
        let owner = motion_bits(a.instances(0)[0]);
        for inst in a.instances(0).into_iter().chain(b.instances(0)) {
            assert_eq!(
                motion_bits(inst),
                owner,
                "a copy left its owner at {clock:?}"
            );
        }
        if stats.iter().any(|s| s.active_nodes > 0) {
            touched += 1;
        }
    }
    assert!(
        touched > 50,
        "the balls never pressed on the plate ({touched} steps)"
    );
    // every body moves exactly as in the single group
    for body in &one.bodies {
        let id = body.def.id;
        let held = if id == 2 { &b } else { &a };
        assert_eq!(
            motion_bits(held.instances(id)[0]),
            motion_bits(body),
            "body {id}"
        );
    }
    assert_eq!(a.body_count() + b.body_count(), 3, "copies are not counted");
}

/// Reactions and history nodes travel only with the steps the master marks due, and
/// leaving them out changes nothing else (the same state bits as the core's group
/// reporting every step).
#[test]
fn reactions_and_history_nodes_are_reported_only_on_due_steps() {
    let mut e = Engine::new();
    let s = Setup {
        reactions: true,
        probes: std::sync::Arc::new(vec![(0, 3)]),
        ..setup()
    };
    ack(e.handle(Command::Setup(s.clone())));
    ack(e.handle(Command::Load {
        at: Clock::default(),
        bodies: bodies().into_iter().map(BodyLoad::whole).collect(),
    }));
    ack(e.handle(Command::regroup(vec![vec![0, 1]])));
    assert!(matches!(e.handle(Command::Start), Reply::Report(_)));
    let mut g = Group::new(bodies(), s.gravity);
    g.reactions = true;
    g.probes = vec![(0, 3)];
    g.start().unwrap();
    let mut clock = Clock::default();
    for k in 0..12 {
        let due = crash_core::Due {
            reactions: k % 3 == 0,
            probes: k % 4 == 0,
        };
        let Reply::Report(rep) = e.handle(Command::Step {
            at: clock,
            dt: 1e-7,
            kin_nodes: false,
            due,
            contact: Default::default(),
            direct: false,
        }) else {
            panic!("no report")
        };
        let core = g.advance(&clock, 1e-7).unwrap();
        assert_eq!(rep.bodies[0].reaction.is_some(), due.reactions, "step {k}");
        assert_eq!(!rep.probes.is_empty(), due.probes, "step {k}");
        if due.reactions {
            assert_eq!(rep.bodies, core, "step {k}");
        }
        if due.probes {
            assert_eq!(rep.probes, g.probed(), "step {k}");
        }
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
}
