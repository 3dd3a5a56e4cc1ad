//! Round trips through the wire format (crash-proto's bodies, reports and faults;
//! crash-link's commands and replies) must be bit-exact.
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_core::body::NodalLoad;
use crash_core::contact::sweep::Momentum;
use crash_core::partition::{PairSpeed, PartDt, PartState, SplitFigures};
use crash_core::shapes::{icosphere, plate, ElementKind};
use crash_core::{
    dof, hash::state_hash, Body, BodyReport, Clock, Fault, Group, Material, Section, Stabilization,
    Vec3, VelocityProgram,
};
use crash_link::wire::{
    command_from_pb, command_to_pb, reply_from_pb, reply_to_pb, report_from_pb,
};
use crash_link::{BodyLoad, Command, GroupTime, Reply, SplitSpec, StepReport};
use crash_proto::pb::worker_message::Reply as PbReply;
use crash_proto::report::{fault_from_pb, fault_to_pb};
use crash_proto::{body_from_pb, body_to_pb};
use prost::Message;

fn steel() -> Section {
    Section::new(Material::new(7800.0, 200e9, 0.3, 1e-7).unwrap(), 0.002)
}

/// A plate of quads with a clamped edge, a moving edge and a load, and a sphere of
/// triangles, both after some steps (so that every state array holds non-zero bits).
fn evolved_bodies() -> Vec<Body> {
    let mut p = Body::new(
        0,
        "plate",
        &plate(0.2, 0.1, 6, 3, ElementKind::Quad),
        steel(),
        Stabilization::default(),
    )
    .unwrap();
    p.fix(0, dof::ALL);
    p.fix(7, dof::X | dof::RZ);
    p.prescribe(
        &[6, 13],
        VelocityProgram {
            displacement: false,
            velocity: Vec3::new(0.0, 0.0, 1.5),
            angular: Vec3::new(0.1, 0.0, 0.0),
            ramp: 1e-5,
            curve: crash_core::NO_CURVE,
        },
    );
    p.add_load(NodalLoad {
        node: 20,
        force: Vec3::new(1.0, -2.0, 30.0),
        moment: Vec3::new(0.0, 0.01, 0.0),
        t0: 0.0,
        t1: 2e-5,
        curve: crash_core::NO_CURVE,
    });
    // a load curve (a table, not a ramp) on a load and a program
    let c = p
        .add_curve(crash_core::TimeCurve {
            points: vec![(0.0, 0.0), (1e-5, 2.0), (3e-5, -1.0)],
        })
        .unwrap();
    p.add_load(NodalLoad {
        node: 9,
        force: Vec3::new(0.0, 0.0, -4.0),
        moment: Vec3::zeros(),
        t0: 0.0,
        t1: 0.0,
        curve: c,
    });
    p.prescribe(
        &[17],
        VelocityProgram {
            // a displacement program: the wire carries its kind
            displacement: true,
            velocity: Vec3::new(0.5e-3, 0.0, 0.0),
            angular: Vec3::zeros(),
            ramp: 0.0,
            curve: c,
        },
    );
    p.def_mut().mass_damping = 3.0;
    p.def_mut().contact = true;
    p.def_mut().self_contact = true;
    let mut s = Body::new(
        1,
        "ball",
        &icosphere(0.05, 1),
        steel(),
        Stabilization::default(),
    )
    .unwrap();
    s.set_rigid_velocity(
        Vec3::new(1.0, 0.0, -4.0),
        Vec3::new(0.0, 30.0, 0.0),
        Vec3::zeros(),
    );
    let mut g = Group::new(vec![p, s], Vec3::new(0.0, 0.0, -9.81));
    g.start().unwrap();
    let mut clock = Clock::default();
    for _ in 0..25 {
        g.advance(&clock, 2e-7).unwrap();
        clock = clock.after(2e-7);
    }
    for b in &mut g.bodies {
        // Contact forces are written by the contact stage; give them non-trivial bits.
        b.state.f_contact = (0..b.state.x.len())
            .map(|i| Vec3::new(i as f64 * 0.1, -1e-300, 3.0))
            .collect();
    }
    g.bodies
}

fn json(b: &Body) -> String {
    serde_json::to_string(b).unwrap()
}

#[test]
fn body_round_trip_keeps_every_field_bit_exact() {
    for b in evolved_bodies() {
        let bytes = body_to_pb(&b).encode_to_vec();
        let back = body_from_pb(&crash_proto::pb::Body::decode(bytes.as_slice()).unwrap()).unwrap();
        assert_eq!(json(&b), json(&back), "body {}", b.def.name);
        assert!(!b.state.hourglass.is_empty() || b.def.name == "ball");
    }
}

#[test]
fn migrated_bodies_continue_bit_identically() {
    let bodies = evolved_bodies();
    let copies: Vec<Body> = bodies
        .iter()
        .map(|b| body_from_pb(&body_to_pb(b)).unwrap())
        .collect();
    let mut a = Group::new(bodies, Vec3::new(0.0, 0.0, -9.81));
    let mut b = Group::new(copies, Vec3::new(0.0, 0.0, -9.81));
    let mut clock = Clock {
        step: 25,
        time: 25.0 * 2e-7,
        last_dt: 2e-7,
    };
    for _ in 0..40 {
        let ra = a.advance(&clock, 2.1e-7).unwrap();
        let rb = b.advance(&clock, 2.1e-7).unwrap();
        assert_eq!(ra, rb);
        clock = clock.after(2.1e-7);
    }
    assert_eq!(state_hash(&a.bodies), state_hash(&b.bodies));
}

#[test]
fn corrupt_state_is_refused_not_panicking() {
    let b = &evolved_bodies()[0];
    let mut m = body_to_pb(b);
    m.state.as_mut().unwrap().x.pop();
    let e = body_from_pb(&m).unwrap_err().to_string();
    assert!(e.contains("'x' has"), "{e}");
    let mut m = body_to_pb(b);
    m.def.as_mut().unwrap().gather_slot[0] = 1_000_000;
    assert!(body_from_pb(&m).is_err());
    let mut m = body_to_pb(b);
    m.def.as_mut().unwrap().program[3] = 7;
    assert!(body_from_pb(&m).is_err());
}

#[test]
fn every_fault_variant_round_trips() {
    let faults = [
        Fault::NonFinite {
            step: 3,
            body: 4,
            place: "node 7".into(),
            what: "velocity or position",
        },
        Fault::Collapsed {
            step: 1,
            body: 2,
            element: 3,
            ratio: 1e-4,
        },
        Fault::Inverted {
            step: 1,
            body: 2,
            element: 3,
            corner: 2,
        },
        Fault::EnergyRunaway {
            step: 9,
            error: 0.3,
            limit: 0.25,
            body: 1,
            element: 17,
        },
        Fault::DtCollapse {
            step: 9,
            dt: 1e-12,
            floor: 1e-10,
            body: 1,
            element: 5,
        },
        Fault::Tunnelling {
            step: 2,
            body: 0,
            node: 11,
            speed: 400.0,
            distance: 1e-3,
            budget: 5e-4,
        },
    ];
    for f in faults {
        let bytes = fault_to_pb(&f).encode_to_vec();
        let back =
            fault_from_pb(&crash_proto::pb::Fault::decode(bytes.as_slice()).unwrap()).unwrap();
        assert_eq!(f, back);
        assert_eq!(f.to_string(), back.to_string());
    }
}

#[test]
fn step_report_round_trips_bit_exact() {
    let mut g = Group::new(evolved_bodies(), Vec3::zeros());
    g.reactions = true;
    g.probes = vec![(0, 1), (0, 3)];
    let mut bodies: Vec<BodyReport> = g.advance(&Clock::default(), 1e-7).unwrap();
    // a reaction on one body (the wire carries them for some bodies only)
    bodies[0].reaction = Some(crash_core::Reaction {
        force: Vec3::new(1.5, -2.0, 1e-300),
        moment: Vec3::new(0.0, 3.0, -0.5),
        moment_origin: Vec3::new(-7.0, 0.125, f64::MIN_POSITIVE),
    });
    let probes = g.probed().to_vec();
    assert_eq!(probes.len(), 2);
    let rep = StepReport {
        probes,
        bodies,
        parts: vec![part_state()],
        split_limits: vec![(3, 1.25e-7), (7, f64::MIN_POSITIVE)],
        part_dts: SplitFigures {
            dts: vec![PartDt {
                id: 3,
                dt: 2.5e-7,
                element: 41,
            }],
            pairs: vec![PairSpeed {
                a: 3,
                b: 7,
                c: 1.5e-3,
                max: [0.0, 1.0 / 3.0, 2.5e300, f64::MIN_POSITIVE],
            }],
        },
        groups: vec![GroupTime {
            first: 0,
            nanos: 12345,
        }],
        compute_ns: 99,
        codec_ns: 17,
        contacts: vec![crash_core::contact::PairStats {
            a: 0,
            b: 1,
            active_nodes: 7,
            max_penetration: 1.5e-5,
            max_penetration_ratio: 0.0075,
            normal_force: 123.456,
            force_on_a: Vec3::new(-1.0, 0.25, 1e-300),
            tally: crash_core::contact::Tally {
                normal: i128::MAX - 5,
                on_a: [-1, i128::MIN, 1 << 100],
            },
            kin_a: Default::default(),
            kin_b: crash_core::contact::KinLoad {
                power: -3.5e-7,
                by_program: vec![
                    (0, Vec3::new(1.0, -2.0, 0.5)),
                    (3, Vec3::new(0.0, 0.0, -7.25)),
                ],
                nodes: vec![
                    (4, Vec3::new(0.5, 0.0, -1.0)),
                    (90_000, Vec3::new(0.0, 1e-300, 2.0)),
                ],
            },
        }],
        split_contacts: vec![crash_core::contact::PairStats {
            a: 3,
            b: 7,
            active_nodes: 2,
            max_penetration: 2.5e-6,
            max_penetration_ratio: 0.001,
            normal_force: 0.5,
            force_on_a: Vec3::new(0.0, 0.0, -0.5),
            tally: crash_core::contact::Tally {
                normal: 1 << 63,
                on_a: [0, 0, -(1 << 63)],
            },
            kin_a: Default::default(),
            kin_b: Default::default(),
        }],
        halo: None,
    };
    let msg = reply_to_pb(&Reply::Report(rep.clone()));
    let bytes = msg.encode_to_vec();
    let back = crash_proto::pb::WorkerMessage::decode(bytes.as_slice()).unwrap();
    let Some(PbReply::Report(r)) = back.reply else {
        panic!("not a report")
    };
    let got = report_from_pb(&r).unwrap();
    assert_eq!(got, rep);
    for (a, b) in got.bodies.iter().zip(&rep.bodies) {
        assert_eq!(a.stable_dt.to_bits(), b.stable_dt.to_bits());
        assert_eq!(a.energy.kinetic.to_bits(), b.energy.kinetic.to_bits());
    }
    // a fault carries the share of the pass it ran (an empty one is a share too) or none
    let fault_with = |split_contacts| Reply::Fault {
        group_first: 3,
        fault: Fault::DtCollapse {
            step: 9,
            dt: 1e-12,
            floor: 1e-10,
            body: 3,
            element: 1,
        },
        split_contacts,
    };
    for share in [Some(rep.split_contacts.clone()), Some(Vec::new()), None] {
        let fault = fault_with(share.clone());
        let bytes = reply_to_pb(&fault).encode_to_vec();
        let back =
            reply_from_pb(&crash_proto::pb::WorkerMessage::decode(bytes.as_slice()).unwrap())
                .unwrap();
        let Reply::Fault { split_contacts, .. } = back else {
            panic!("not a fault")
        };
        assert_eq!(split_contacts, share);
    }
    // a Step's report carries the outcome of a direct halo: a report, a fault, an
    // error or why the direct exchange failed
    let halo_fault = fault_with(Some(rep.split_contacts.clone()));
    for halo in [
        crash_link::Halo::Report(Box::new(rep.clone())),
        crash_link::Halo::from_reply(halo_fault),
        crash_link::Halo::Error("no step in flight".into()),
        crash_link::Halo::Lost("worker 1 (10.0.0.2:4000): the connection closed".into()),
    ] {
        let with = StepReport {
            halo: Some(Box::new(halo)),
            ..StepReport::default()
        };
        let bytes = reply_to_pb(&Reply::Report(with.clone())).encode_to_vec();
        let back = crash_proto::pb::WorkerMessage::decode(bytes.as_slice()).unwrap();
        let Some(PbReply::Report(r)) = back.reply else {
            panic!("not a report")
        };
        assert_eq!(report_from_pb(&r).unwrap(), with);
    }
}

#[test]
fn commands_round_trip() {
    let bodies = evolved_bodies();
    let at = Clock {
        step: 41,
        time: 8.2e-6,
        last_dt: 1.9e-7,
    };
    let loads = || {
        bodies
            .iter()
            .cloned()
            .map(BodyLoad::whole)
            .collect::<Vec<_>>()
    };
    let cmds = [
        Command::Setup(crash_link::Setup {
            gravity: Vec3::new(0.0, 0.0, -9.81),
            contact: Default::default(),
            reactions: true,
            probes: std::sync::Arc::new(vec![(0, 4), (1, 2)]),
        }),
        Command::regroup(vec![vec![0, 3, 9], vec![1], vec![2, 4]]),
        Command::Regroup {
            groups: vec![vec![0, 3, 9], vec![1], vec![2, 4]],
            copies: vec![vec![7], vec![], vec![7, 8]],
        },
        Command::Lend {
            ids: vec![7],
            with_def: vec![],
        },
        Command::Step {
            at,
            dt: 1.234e-7,
            kin_nodes: true,
            due: crash_core::Due {
                reactions: true,
                probes: false,
            },
            contact: Default::default(),
            direct: true,
        },
        Command::Unload {
            ids: vec![5, 2],
            with_def: vec![2],
        },
        Command::Load {
            at,
            bodies: loads(),
        },
        Command::Frame(vec![1, 0]),
        Command::States(vec![3, 1]),
        Command::Reset,
        Command::Shutdown("done".into()),
    ];
    for c in cmds {
        let bytes = command_to_pb(&c, |_| false).encode_to_vec();
        let back =
            command_from_pb(&crash_proto::pb::MasterMessage::decode(bytes.as_slice()).unwrap())
                .unwrap();
        match (&c, &back) {
            (Command::Load { at: ta, bodies: a }, Command::Load { at: tb, bodies: b }) => {
                assert!(ta.same_as(tb));
                assert_eq!(a.len(), b.len());
                for (x, y) in a.iter().zip(b) {
                    let (x, y) = (
                        x.clone().into_body(None).unwrap(),
                        y.clone().into_body(None).unwrap(),
                    );
                    assert_eq!(json(&x), json(&y));
                }
            }
            _ => assert_eq!(format!("{c:?}"), format!("{back:?}")),
        }
    }
}

#[test]
fn a_definition_the_worker_holds_is_not_sent_again() {
    let bodies = evolved_bodies();
    let load = Command::Load {
        at: Clock::default(),
        bodies: bodies.iter().cloned().map(BodyLoad::whole).collect(),
    };
    let first = command_to_pb(&load, |_| false).encode_to_vec().len();
    let again = command_to_pb(&load, |_| true).encode_to_vec().len();
    let defs: usize = bodies
        .iter()
        .map(|b| crash_proto::def_to_pb(&b.def).encode_to_vec().len())
        .sum();
    assert!(
        again + defs <= first,
        "states only: {again} bytes, with definitions {first} (definitions {defs})"
    );
    let back = command_from_pb(&command_to_pb(&load, |_| true)).unwrap();
    let Command::Load { bodies: b, .. } = back else {
        panic!("not a load")
    };
    // joined with the definitions held, the states give back the same bodies
    for (orig, l) in bodies.iter().zip(b) {
        assert!(l.def.is_none());
        let body = l.into_body(Some(&orig.def)).unwrap();
        assert_eq!(json(orig), json(&body));
    }
}

#[test]
fn frames_and_states_round_trip_bit_exact() {
    let bodies = evolved_bodies();
    let frame: Vec<crash_io::FrameBody> = bodies.iter().map(crash_io::FrameBody::capture).collect();
    let msg = reply_to_pb(&Reply::Frame(frame.clone()));
    let back = reply_from_pb(
        &crash_proto::pb::WorkerMessage::decode(msg.encode_to_vec().as_slice()).unwrap(),
    )
    .unwrap();
    let Reply::Frame(got) = back else {
        panic!("not a frame")
    };
    assert_eq!(got, frame);
    let states: Vec<(u32, crash_core::BodyState)> =
        bodies.iter().map(|b| (b.def.id, b.state.clone())).collect();
    let msg = reply_to_pb(&Reply::States(states.clone()));
    let Reply::States(got) = reply_from_pb(&msg).unwrap() else {
        panic!("not states")
    };
    assert_eq!(got, states);
}

/// A part's frame share (v19) and its request round-trip bit for bit; a share whose
/// arrays do not match its node and element lists is refused.
#[test]
fn part_frame_shares_round_trip_bit_exact_and_inconsistent_ones_are_refused() {
    let b = &evolved_bodies()[0];
    let nodes: Vec<u32> = (0..b.state.x.len() as u32).collect();
    let elements: Vec<u32> = (0..b.def.element_count() as u32).rev().collect();
    let share = crash_io::PartFrame::capture(b.def.id, b, nodes.len(), &nodes, &elements);
    let msg = reply_to_pb(&Reply::PartFrames(vec![share.clone()]));
    let back = reply_from_pb(
        &crash_proto::pb::WorkerMessage::decode(msg.encode_to_vec().as_slice()).unwrap(),
    )
    .unwrap();
    let Reply::PartFrames(got) = back else {
        panic!("not frame shares")
    };
    assert_eq!(got, vec![share]);
    let cmd = command_to_pb(&Command::PartFrames(vec![3, 1]), |_| false);
    assert!(matches!(command_from_pb(&cmd).unwrap(), Command::PartFrames(ids) if ids == [3, 1]));
    let mut bad = msg;
    if let Some(crash_proto::pb::worker_message::Reply::PartFrames(f)) = bad.reply.as_mut() {
        f.parts[0].nodes.pop();
    }
    assert!(reply_from_pb(&bad).is_err());
}

#[test]
fn regroup_with_inconsistent_sizes_is_refused() {
    let mut m = command_to_pb(&Command::regroup(vec![vec![0, 1], vec![2]]), |_| false);
    if let Some(crash_proto::pb::master_message::Command::Regroup(r)) = m.command.as_mut() {
        r.sizes[1] = 5;
    }
    assert!(command_from_pb(&m).is_err());
}

fn part_state() -> PartState {
    PartState {
        id: 3,
        part: 1,
        x: vec![
            Vec3::new(0.1, -2.5e-300, 7.0),
            Vec3::new(-0.0, 1.0, f64::MAX),
        ],
        v: vec![Vec3::new(-4.0, 5.5, 1e-310)],
        w: vec![Vec3::new(0.0, 0.0, 0.25), Vec3::new(9.0, -1.0 / 3.0, 2.0)],
        lo: Vec3::new(-1.0, f64::MIN_POSITIVE, 0.5),
        hi: Vec3::new(2.0, 1e300, -0.0),
        far: 3.0e-4,
        max_move: 1.0 / 7.0,
        max_move_node: 41,
        momentum: Momentum([i64::MIN, -1, i64::MAX]),
    }
}

/// The split-group commands and replies (protocol v9) cross the wire with every bit.
#[test]
fn split_group_commands_and_replies_round_trip_bit_exact() {
    let spec = SplitSpec {
        ids: vec![2, 3, 9],
        parts: vec![2, 1, 2],
        holder: vec![vec![0, 1], vec![1], vec![0, 1]],
        slot: 1,
        workers: vec![0, 1],
        peers: vec!["127.0.0.1:4000".into(), String::new()],
    };
    let bodies = evolved_bodies();
    let dts = SplitFigures {
        dts: vec![
            PartDt {
                id: 2,
                dt: 1.0 / 3.0 * 1e-7,
                element: 17,
            },
            PartDt {
                id: 9,
                dt: f64::INFINITY,
                element: 0,
            },
        ],
        pairs: vec![PairSpeed {
            a: 2,
            b: 9,
            c: 1e-3,
            max: [4.0, 0.5, 1e-9, 3.25],
        }],
    };
    let states: Vec<(u32, u32, crash_core::BodyState)> = bodies
        .iter()
        .enumerate()
        .map(|(k, b)| (b.def.id, k as u32, b.state.clone()))
        .collect();
    let cmds = vec![
        Command::Split(spec.clone()),
        Command::Share {
            at: Clock::default().after(1e-7),
            spec,
            bodies: bodies.iter().cloned().map(BodyLoad::whole).collect(),
        },
        Command::Halo(vec![part_state(), part_state()]),
        Command::Contact(dts.clone()),
        Command::Step {
            at: Clock::default().after(1e-7),
            dt: 2e-7,
            kin_nodes: false,
            due: crash_core::Due::ALL,
            contact: dts.clone(),
            direct: false,
        },
        Command::Parts,
        Command::Assemble(states.clone()),
        Command::Unsplit,
    ];
    for c in cmds {
        let bytes = command_to_pb(&c, |_| false).encode_to_vec();
        let back =
            command_from_pb(&crash_proto::pb::MasterMessage::decode(bytes.as_slice()).unwrap())
                .unwrap();
        assert_eq!(format!("{back:?}"), format!("{c:?}"));
    }
    let halo = Reply::Report(StepReport {
        part_dts: dts,
        ..Default::default()
    });
    for r in [halo, Reply::Parts(states)] {
        let bytes = reply_to_pb(&r).encode_to_vec();
        let back =
            reply_from_pb(&crash_proto::pb::WorkerMessage::decode(bytes.as_slice()).unwrap())
                .unwrap();
        assert_eq!(format!("{back:?}"), format!("{r:?}"));
    }
}

/// A part state's block of points (protocol v13) must hold exactly the points it states:
/// a short or long block is refused, not read past or padded.
#[test]
fn a_part_state_whose_points_do_not_match_their_counts_is_refused() {
    let good = command_to_pb(&Command::Halo(vec![part_state()]), |_| false);
    assert!(command_from_pb(&good).is_ok());
    type Change = fn(&mut crash_proto::pb::PartState);
    let changes: [Change; 2] = [|p| p.nv += 1, |p| p.xvw.truncate(p.xvw.len() - 1)];
    for change in changes {
        let mut m = good.clone();
        if let Some(crash_proto::pb::master_message::Command::Halo(h)) = m.command.as_mut() {
            change(&mut h.parts[0]);
        }
        let e = command_from_pb(&m).expect_err("refused");
        assert!(e.to_string().contains("part 1 of body 3"), "{e}");
    }
}

/// A frame between two holders (protocol v18) carries the step and the part states
/// bit for bit, or the sender's stop.
#[test]
fn a_peer_halo_frame_round_trips_its_step_and_parts_or_its_stop() {
    use crash_link::wire::{peer_halo_from_pb, peer_halo_to_pb};
    let parts = vec![part_state(), part_state()];
    let bytes = peer_halo_to_pb(77, Some(&parts)).encode_to_vec();
    let back = crash_proto::pb::PeerHalo::decode(bytes.as_slice()).unwrap();
    let (step, got) = peer_halo_from_pb(&back).unwrap();
    assert_eq!(step, 77);
    assert_eq!(format!("{got:?}"), format!("{:?}", Some(parts)));
    let stop = peer_halo_to_pb(78, None).encode_to_vec();
    let back = crash_proto::pb::PeerHalo::decode(stop.as_slice()).unwrap();
    assert!(matches!(peer_halo_from_pb(&back), Ok((78, None))));
}
