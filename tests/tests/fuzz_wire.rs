//! Proptest targets of what crosses the network (issue 14 point 6): the wire decoder
//! (bytes -> generated message -> Command or Reply) and every command handler of the
//! worker engine. Mutated encodings of real commands and replies, random bytes, and
//! arbitrary command sequences (real bodies, wrong ids, states cut short, clocks and
//! steps of any value) give a value or a typed error (`Reply::Error`), never a panic.
//! `CRASH_FUZZ_CASES` cases per target (default 10 000); messages below 64 KiB.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_core::{Body, Clock, Vec3};
use crash_link::wire::{command_from_pb, command_to_pb, reply_from_pb, reply_to_pb};
use crash_link::{BodyLoad, Command, Setup};
use crash_proto::pb;
use crash_tests::fixtures::test_scene;
use crash_tests::mutate::{config, mutated, random};
use crash_worker::Engine;
use proptest::prelude::*;
use prost::Message;
use std::sync::OnceLock;

const LIMIT: usize = 64 << 10;

/// The two spheres of the cluster tests (320 triangles each) and the scene's setup.
fn scene() -> &'static (Vec<Body>, Setup) {
    static S: OnceLock<(Vec<Body>, Setup)> = OnceLock::new();
    S.get_or_init(|| {
        let b = crash_scene::load(&test_scene("two-spheres-tiny.toml"))
            .unwrap()
            .build()
            .unwrap();
        // reactions and a history node on: their code runs in the sequences too
        let setup = Setup {
            gravity: b.gravity,
            contact: b.contact,
            reactions: true,
            probes: std::sync::Arc::new(vec![(0, 1), (1, 2)]),
        };
        (b.bodies, setup)
    })
}

/// An engine holding both spheres in one group, started.
fn started() -> Engine {
    let (bodies, setup) = scene();
    let mut e = Engine::new();
    e.handle(Command::Setup(setup.clone()));
    e.handle(Command::Load {
        at: Clock::default(),
        bodies: bodies.iter().cloned().map(BodyLoad::whole).collect(),
    });
    e.handle(Command::Regroup {
        groups: vec![vec![0, 1]],
        copies: Vec::new(),
    });
    e.handle(Command::Start);
    e
}

/// Encoded commands of a real session: setup, load, regroup, step, frame, states.
fn valid_commands() -> Vec<Vec<u8>> {
    let (bodies, setup) = scene();
    let at = Clock::default();
    let cmds = [
        Command::Setup(setup.clone()),
        Command::Load {
            at,
            bodies: vec![BodyLoad::whole(bodies[0].clone())],
        },
        Command::Unload {
            ids: vec![0, 1],
            with_def: vec![1],
        },
        Command::Regroup {
            groups: vec![vec![0], vec![1]],
            copies: vec![vec![], vec![0]],
        },
        Command::Step {
            at,
            dt: 1e-7,
            kin_nodes: true,
            due: crash_core::Due::ALL,
            contact: Default::default(),
            direct: false,
        },
        Command::Frame(vec![0, 1]),
        Command::States(vec![1]),
    ];
    cmds.iter()
        .map(|c| command_to_pb(c, |id| id == 1).encode_to_vec())
        .filter(|b| b.len() < LIMIT)
        .collect()
}

/// Encoded replies of a real session: a report, a frame, states, a fault.
fn valid_replies() -> Vec<Vec<u8>> {
    let mut e = started();
    let mut out = vec![e.handle(Command::Step {
        at: Clock::default(),
        dt: 1e-7,
        kin_nodes: true,
        due: crash_core::Due::ALL,
        contact: Default::default(),
        direct: false,
    })];
    out.push(e.handle(Command::Frame(vec![0])));
    let at = e.clock().unwrap();
    out.push(e.handle(Command::States(vec![1])));
    // a blow-up: a step far above the stable one
    out.push(e.handle(Command::Step {
        at,
        dt: 1.0,
        kin_nodes: false,
        due: crash_core::Due::ALL,
        contact: Default::default(),
        direct: false,
    }));
    out.iter()
        .map(|r| reply_to_pb(r).encode_to_vec())
        .filter(|b| b.len() < LIMIT)
        .collect()
}

fn decode_command(bytes: &[u8]) -> Option<Command> {
    let m = pb::MasterMessage::decode(bytes).ok()?;
    command_from_pb(&m).ok()
}

fn decode_reply(bytes: &[u8]) {
    if let Ok(m) = pb::WorkerMessage::decode(bytes) {
        let _ = reply_from_pb(&m);
    }
}

/// One step of a command sequence; `None` fields are filled from the engine's state,
/// so sequences reach the stepping code.
#[derive(Debug, Clone)]
enum Op {
    Setup(Option<Vec3>),
    /// Bodies (index, keep the definition, id offset, nodes cut from the state).
    Load(Option<Clock>, Vec<(usize, bool, u32, usize)>),
    Unload(Vec<u32>, Vec<u32>),
    /// Unload that keeps the bodies (for copies elsewhere).
    Lend(Vec<u32>, Vec<u32>),
    /// Read-only copies (like Load).
    LoadCopies(Option<Clock>, Vec<(usize, bool, u32, usize)>),
    /// Groups and their copies.
    Regroup(Vec<Vec<u32>>, Vec<Vec<u32>>),
    Start,
    Step(Option<Clock>, f64, bool),
    Frame(Vec<u32>),
    States(Vec<u32>),
    Reset,
    Shutdown,
    /// A mutated real command, through the decoder.
    Wire(Vec<u8>),
}

fn float() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(1e-7),
        Just(1e-6),
        Just(0.0),
        Just(-1e-7),
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(1e300),
        Just(f64::MIN_POSITIVE),
        any::<f64>(),
    ]
}

fn clock() -> impl Strategy<Value = Option<Clock>> {
    prop_oneof![
        3 => Just(None),
        1 => Just(Some(Clock::default())),
        1 => (any::<u64>(), float(), float()).prop_map(|(step, time, last_dt)| Some(Clock {
            step,
            time,
            last_dt
        })),
    ]
}

fn ids() -> impl Strategy<Value = Vec<u32>> {
    proptest::collection::vec(prop_oneof![4 => 0u32..3, 1 => any::<u32>()], 0..4)
}

fn op(wire: Vec<Vec<u8>>) -> impl Strategy<Value = Op> {
    let vec3 = (float(), float(), float()).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    let body = (
        0usize..2,
        any::<bool>(),
        prop_oneof![4 => Just(0u32), 1 => 0u32..3],
        prop_oneof![4 => Just(0usize), 1 => 1usize..5],
    );
    prop_oneof![
        2 => proptest::option::of(vec3).prop_map(Op::Setup),
        3 => (clock(), proptest::collection::vec(body.clone(), 0..3)).prop_map(|(c, b)| Op::Load(c, b)),
        1 => (ids(), ids()).prop_map(|(a, b)| Op::Unload(a, b)),
        1 => (ids(), ids()).prop_map(|(a, b)| Op::Lend(a, b)),
        1 => (clock(), proptest::collection::vec(body, 0..3)).prop_map(|(c, b)| Op::LoadCopies(c, b)),
        3 => (prop_oneof![
            Just(vec![vec![0, 1]]),
            Just(vec![vec![0], vec![1]]),
            proptest::collection::vec(ids(), 0..3),
        ], proptest::collection::vec(ids(), 0..3)).prop_map(|(g, c)| Op::Regroup(g, c)),
        2 => Just(Op::Start),
        4 => (clock(), float(), proptest::bool::ANY).prop_map(|(c, dt, k)| Op::Step(c, dt, k)),
        1 => ids().prop_map(Op::Frame),
        1 => ids().prop_map(Op::States),
        1 => Just(Op::Reset),
        1 => Just(Op::Shutdown),
        2 => proptest::sample::select(wire)
            .prop_flat_map(|w| mutated(w, LIMIT))
            .prop_map(Op::Wire),
    ]
}

/// Bodies of the scene (index, keep the definition, id offset, nodes cut from the state).
fn loads(bodies: &[Body], list: Vec<(usize, bool, u32, usize)>) -> Vec<BodyLoad> {
    list.into_iter()
        .map(|(i, def, shift, cut)| {
            let b = bodies[i].clone();
            let mut state = b.state;
            let n = state.x.len().saturating_sub(cut);
            state.x.truncate(n);
            BodyLoad {
                id: b.def.id + shift,
                def: def.then_some(b.def),
                state,
            }
        })
        .collect()
}

fn command(e: &Engine, op: Op) -> Option<Command> {
    let (bodies, setup) = scene();
    let now = e.clock().unwrap_or_default();
    Some(match op {
        Op::Setup(g) => Command::Setup(Setup {
            gravity: g.unwrap_or(setup.gravity),
            ..setup.clone()
        }),
        Op::Load(at, list) => Command::Load {
            at: at.unwrap_or(now),
            bodies: loads(bodies, list),
        },
        Op::Unload(ids, with_def) => Command::Unload { ids, with_def },
        Op::Lend(ids, with_def) => Command::Lend { ids, with_def },
        Op::LoadCopies(at, list) => Command::LoadCopies {
            at: at.unwrap_or(now),
            bodies: loads(bodies, list),
        },
        Op::Regroup(groups, copies) => Command::Regroup { groups, copies },
        Op::Start => Command::Start,
        Op::Step(at, dt, kin_nodes) => Command::Step {
            at: at.unwrap_or(now),
            dt,
            kin_nodes,
            due: crash_core::Due::ALL,
            contact: Default::default(),
            direct: false,
        },
        Op::Frame(ids) => Command::Frame(ids),
        Op::States(ids) => Command::States(ids),
        Op::Reset => Command::Reset,
        Op::Shutdown => Command::Shutdown("fuzz".into()),
        Op::Wire(b) => decode_command(&b)?,
    })
}

fn valid_wire() -> &'static Vec<Vec<u8>> {
    static W: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    W.get_or_init(valid_commands)
}

fn valid_reply_bytes() -> &'static Vec<Vec<u8>> {
    static W: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    W.get_or_init(valid_replies)
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn wire_decoder_never_panics_on_mutated_commands(
        b in proptest::sample::select(valid_wire().clone()).prop_flat_map(|w| mutated(w, LIMIT))
    ) {
        let _ = decode_command(&b);
    }

    #[test]
    fn wire_decoder_never_panics_on_mutated_replies(
        b in proptest::sample::select(valid_reply_bytes().clone()).prop_flat_map(|w| mutated(w, LIMIT))
    ) {
        decode_reply(&b);
    }

    #[test]
    fn wire_decoder_never_panics_on_random_bytes(b in random(4096)) {
        let _ = decode_command(&b);
        decode_reply(&b);
    }

    #[test]
    fn engine_answers_any_command_sequence_without_panicking(
        ops in proptest::collection::vec(op(valid_wire().clone()), 1..10),
        started_first: bool,
    ) {
        let mut e = if started_first { started() } else { Engine::new() };
        for o in ops {
            if let Some(c) = command(&e, o) {
                // any reply is fine: a panic fails the test
                let _ = e.handle(c);
            }
        }
    }
}
