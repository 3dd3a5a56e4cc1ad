//! Domain decomposition, second layer (issue 16 point 2): contact across parts. A group
//! of bodies in contact, each split into parts that see the other bodies (and their own
//! body's other parts) through a contact view, steps bit-identically to the whole group:
//! every node's x, v, w after every step, the stable step before it and the contact
//! statistics of every pair (contacts.csv: each push booked once, by the part owning
//! its slave node), through the impact and rebound of a sphere dropped on a clamped
//! plate.

mod contact_util;

use contact_util::*;
use crash_core::contact::{ContactConfig, ContactPass};
use crash_core::hash::state_hash;
use crash_core::partition::{GroupSplit, ViewRule};
use crash_core::shapes::{plate, ElementKind};
use crash_core::{dof, Body, Clock, Group, Vec3};

const SAFETY: f64 = 0.9;
/// Long enough for the sphere to hit the plate, press in and leave it (checked).
const END: f64 = 1.5e-3;

fn config() -> ContactConfig {
    ContactConfig {
        margin: 1e-3,
        ..Default::default()
    }
}

/// The showcase, small: a steel icosphere shell (R 0.1 m, t 1 mm, level 3) at 2 m/s
/// towards a 0.3 m steel plate of 16 x 16 quads, t 2 mm, clamped on its edges, 0.2 mm
/// beyond contact; the sphere's pole hits the plate's centre, where the cuts meet.
fn drop_scene() -> Vec<Body> {
    let (r, t, tp) = (0.05, 0.001, 0.005);
    let z0 = r + 0.5 * (t + tp) + 2e-4;
    // off the axes by a little: the pole is not a mesh symmetry point of the plate
    let s = sphere(
        0,
        r,
        t,
        4,
        Vec3::new(0.003, -0.002, z0),
        Vec3::new(0.0, 0.0, -4.0),
    );
    let lx = 0.2;
    let mut p = shell(1, &plate(lx, lx, 16, 16, ElementKind::Quad), tp);
    for i in 0..p.state.x.len() {
        let x = p.def.x0[i];
        if x.x.abs() > 0.5 * lx - 1e-9 || x.y.abs() > 0.5 * lx - 1e-9 {
            p.fix(i, dof::ALL);
        }
    }
    vec![s, p]
}

/// State hash after each step, the stable step before it, the contact statistics of
/// each step, the most active contact nodes of a step and the final velocity of body
/// 0's centre of mass.
struct Trace {
    hashes: Vec<u64>,
    dts: Vec<f64>,
    contacts: Vec<Vec<[u64; 8]>>,
    active: usize,
    v: Vec3,
    /// Contact pushes summed over the steps (whole group).
    pushes: usize,
}

/// Exact bits of each pair's statistics: ids, pushed nodes, deepest penetration,
/// normal force and the force on body a.
fn stat_bits(stats: &[crash_core::contact::PairStats]) -> Vec<[u64; 8]> {
    stats
        .iter()
        .map(|s| {
            [
                u64::from(s.a) << 32 | u64::from(s.b),
                s.active_nodes as u64,
                s.max_penetration.to_bits(),
                s.max_penetration_ratio.to_bits(),
                s.normal_force.to_bits(),
                s.force_on_a.x.to_bits(),
                s.force_on_a.y.to_bits(),
                s.force_on_a.z.to_bits(),
            ]
        })
        .collect()
}

fn min_dt(r: &[f64]) -> f64 {
    r.iter().copied().fold(f64::INFINITY, f64::min)
}

fn whole_run(bodies: &[Body], end: f64) -> Trace {
    whole_run_with(bodies, end, config())
}

fn whole_run_with(bodies: &[Body], end: f64, cfg: ContactConfig) -> Trace {
    let mut g = Group::new(bodies.to_vec(), Vec3::zeros());
    g.contact = cfg;
    let dts0: Vec<f64> = g
        .start()
        .expect("start")
        .iter()
        .map(|r| r.stable_dt)
        .collect();
    let mut dt = min_dt(&dts0);
    let mut clock = Clock::default();
    let mut t = Trace {
        hashes: Vec::new(),
        dts: Vec::new(),
        contacts: Vec::new(),
        active: 0,
        v: Vec3::zeros(),
        pushes: 0,
    };
    while clock.time < end {
        let h = SAFETY * dt;
        t.dts.push(dt);
        let r = g.advance(&clock, h).expect("stable");
        dt = min_dt(&r.iter().map(|r| r.stable_dt).collect::<Vec<_>>());
        clock = clock.after(h);
        t.hashes.push(state_hash(&g.bodies));
        t.contacts.push(stat_bits(g.contact_stats()));
        let active: usize = g.contact_stats().iter().map(|s| s.active_nodes).sum();
        t.active = t.active.max(active);
        t.pushes += active;
    }
    t.v = com_velocity(&g.bodies[0]);
    t
}

/// The same run with body i in `parts[i]` parts; also the pushes the parts booked
/// (summed over the steps), and the most view nodes (over all views) per owned node.
fn split_run(bodies: &[Body], parts: &[usize], rule: ViewRule, end: f64) -> (Trace, usize, f64) {
    split_run_with_skin(bodies, parts, rule, end, None, config()).0
}

/// `split_run` with the views' skin set (default: the search margin); also the number
/// of view builds.
fn split_run_with_skin(
    bodies: &[Body],
    parts: &[usize],
    rule: ViewRule,
    end: f64,
    skin: Option<f64>,
    cfg: ContactConfig,
) -> ((Trace, usize, f64), u64) {
    let mut g = GroupSplit::new(bodies, parts, cfg, Vec3::zeros(), rule).expect("split");
    if let Some(skin) = skin {
        g.skin = skin;
    }
    let mut whole = bodies.to_vec();
    let mut dt = min_dt(&g.start().expect("start"));
    let mut clock = Clock::default();
    let mut t = Trace {
        hashes: Vec::new(),
        dts: Vec::new(),
        contacts: Vec::new(),
        active: 0,
        v: Vec3::zeros(),
        pushes: 0,
    };
    let (mut pushes, mut per_owned) = (0, 0.0f64);
    while clock.time < end {
        let h = SAFETY * dt;
        t.dts.push(dt);
        match g.advance(&clock, h) {
            Ok(d) => dt = min_dt(&d),
            Err(_) => break, // a broken view may fault: the hashes then differ
        }
        clock = clock.after(h);
        g.gather_into(&mut whole);
        t.hashes.push(state_hash(&whole));
        t.contacts.push(stat_bits(g.contact_stats()));
        pushes += g
            .contact_stats()
            .iter()
            .map(|s| s.active_nodes)
            .sum::<usize>();
        let (view, owned) = g.view_nodes();
        per_owned = per_owned.max(view as f64 / owned as f64);
    }
    t.v = com_velocity(&whole[0]);
    println!("parts {parts:?}: contact views built {} times", g.builds);
    ((t, pushes, per_owned), g.builds)
}

/// First step whose hash or stable step differs, if any.
fn first_difference(got: &Trace, want: &Trace) -> Option<usize> {
    (0..want.hashes.len()).find(|&s| {
        got.hashes.get(s) != Some(&want.hashes[s])
            || got.dts.get(s).map(|d| d.to_bits()) != Some(want.dts[s].to_bits())
    })
}

fn check(parts_of: fn(usize) -> [usize; 2], what: &str) {
    check_with(parts_of, what, config());
}

fn check_with(parts_of: fn(usize) -> [usize; 2], what: &str, cfg: ContactConfig) {
    let bodies = drop_scene();
    let want = whole_run_with(&bodies, END, cfg);
    println!(
        "whole: {} steps, most active nodes {}, pushes {}, final sphere vz {:.3} m/s",
        want.hashes.len(),
        want.active,
        want.pushes,
        want.v.z
    );
    // the run is a real impact: contact, then the sphere moving up
    assert!(want.active >= 5, "contact: {} nodes", want.active);
    assert!(want.v.z > 0.5, "rebound: {} m/s", want.v.z);
    for k in 1..=4 {
        let parts = parts_of(k);
        let (got, pushes, per_owned) =
            split_run_with_skin(&bodies, &parts, ViewRule::default(), END, None, cfg).0;
        assert_eq!(
            got.hashes.len(),
            want.hashes.len(),
            "{what} {parts:?}: steps"
        );
        assert_eq!(
            first_difference(&got, &want),
            None,
            "{what} {parts:?}: first step whose x, v, w or dt differ"
        );
        let stats_differ = (0..want.contacts.len()).find(|&s| got.contacts[s] != want.contacts[s]);
        assert_eq!(
            stats_differ, None,
            "{what} {parts:?}: first step whose contact statistics differ"
        );
        assert_eq!(pushes, want.pushes, "{what} {parts:?}: pushes booked");
        println!(
            "{what}, parts {parts:?}: {} steps bit-identical, final hash {:016x}, contact \
             statistics identical ({pushes} pushes booked); view nodes over all views, \
             most over the run: {per_owned:.2} per node",
            want.hashes.len(),
            want.hashes[want.hashes.len() - 1],
        );
    }
}

#[test]
fn a_sphere_dropped_on_a_split_plate_steps_bit_identically_to_the_whole_group() {
    check(|k| [1, k], "split plate");
}

#[test]
fn a_split_sphere_dropped_on_a_plate_steps_bit_identically_to_the_whole_group() {
    check(|k| [k, 1], "split sphere");
}

#[test]
fn a_split_sphere_dropped_on_a_split_plate_steps_bit_identically_to_the_whole_group() {
    check(|k| [k, k], "both split");
}

/// The segment pass (points between the nodes, loads on the corner normals pulled back
/// to the nodes around them) reaches farther than a node hit: its views hold the second
/// ring of segments around the owned nodes and every master within the bulge reach
/// (`partition::select_points`), the stiffening step is the minimum over the views of
/// the points each counts.
fn segments() -> ContactConfig {
    ContactConfig {
        pass: ContactPass::Segments,
        ..config()
    }
}

#[test]
fn under_the_segment_pass_a_split_plate_steps_bit_identically_to_the_whole_group() {
    check_with(|k| [1, k], "segment pass, split plate", segments());
}

#[test]
fn under_the_segment_pass_split_bodies_step_bit_identically_to_the_whole_group() {
    check_with(|k| [k, k], "segment pass, both split", segments());
}

#[test]
fn under_the_segment_pass_coarse_spheres_in_parts_step_bit_identically_to_the_whole_group() {
    // level 2: segments of about 30 mm, bulges of millimetres, the stiffening law's
    // step sets the clock while the spheres press (checked below)
    let bodies = coarse_head_on();
    let want = whole_run_with(&bodies, HEAD_ON_END, segments());
    let free = whole_run(&bodies, HEAD_ON_END);
    assert!(want.active >= 1, "contact: {} points", want.active);
    assert!(want.v.x < -1.0, "rebound: {} m/s", want.v.x);
    let shortened = want
        .dts
        .iter()
        .filter(|d| **d < free.dts[0] * 0.999)
        .count();
    println!(
        "segment pass head-on: {} steps, {shortened} shortened",
        want.dts.len()
    );
    for k in 1..=3 {
        for skin in [None, Some(1e-4)] {
            let ((got, pushes, _), _) = split_run_with_skin(
                &bodies,
                &[k, k],
                ViewRule::default(),
                HEAD_ON_END,
                skin,
                segments(),
            );
            assert_eq!(
                first_difference(&got, &want),
                None,
                "{k} parts each, skin {skin:?}"
            );
            let stats_differ =
                (0..want.contacts.len()).find(|&s| got.contacts[s] != want.contacts[s]);
            assert_eq!(stats_differ, None, "{k} parts, skin {skin:?}: statistics");
            assert_eq!(
                pushes, want.pushes,
                "{k} parts, skin {skin:?}: points booked"
            );
        }
    }
}

/// Two coarse spheres (level 2: edges of about 30 mm against a reach of 3 mm) closing
/// head-on: a hit's segment corners have segments far outside the reach.
fn coarse_head_on() -> Vec<Body> {
    let (a, b) = head_on_pair(0.1, 0.001, 2, 2e-4, 2.0);
    vec![a, b]
}

const HEAD_ON_END: f64 = 1.5e-3;

#[test]
fn coarse_spheres_closing_head_on_in_parts_step_bit_identically_to_the_whole_group() {
    let bodies = coarse_head_on();
    let want = whole_run(&bodies, HEAD_ON_END);
    println!(
        "head-on whole: {} steps, most active nodes {}, pushes {}, final vx of sphere 0 {:.3} m/s",
        want.hashes.len(),
        want.active,
        want.pushes,
        want.v.x
    );
    assert!(want.active >= 1, "contact: {} nodes", want.active);
    assert!(want.v.x < -1.0, "rebound: {} m/s", want.v.x);
    for k in 1..=4 {
        let (got, _, _) = split_run(&bodies, &[k, k], ViewRule::default(), HEAD_ON_END);
        assert_eq!(first_difference(&got, &want), None, "{k} parts each");
        // a skin of 0.1 mm: the views are rebuilt many times through the contact
        let ((got, _, _), builds) = split_run_with_skin(
            &bodies,
            &[k, k],
            ViewRule::default(),
            HEAD_ON_END,
            Some(1e-4),
            config(),
        );
        assert!(builds > 5, "{builds} builds");
        assert_eq!(
            first_difference(&got, &want),
            None,
            "{k} parts each, skin 0.1 mm"
        );
    }
}

#[test]
fn a_contact_view_without_its_ring_of_segments_breaks_the_bits() {
    // the tests above can fail: without the ring, the normals at a hit segment's far
    // corners miss segments, and the push on owned nodes gets other bits
    let bodies = coarse_head_on();
    let want = whole_run(&bodies, HEAD_ON_END);
    let rule = ViewRule {
        ring: false,
        ..Default::default()
    };
    // (one part each still needs it: the other body's view is partial)
    let broken: Vec<_> = (1..=4)
        .map(|k| first_difference(&split_run(&bodies, &[k, k], rule, HEAD_ON_END).0, &want))
        .collect();
    println!("without the ring, first differing step for 1..4 parts: {broken:?}");
    assert!(broken.iter().all(Option::is_some), "{broken:?}");
}

#[test]
fn with_the_ring_a_views_own_lumped_masses_are_the_whole_bodies_where_hits_read_them() {
    // a view holds every segment at the nodes whose masses a hit reads (slave, segment
    // corners), so the masses it would lump itself equal the copied whole-body ones
    // there: the copy is kept, but no step depends on it (measured, both scenes)
    let rule = ViewRule {
        whole_masses: false,
        ..Default::default()
    };
    for (name, bodies, end) in [
        ("head-on", coarse_head_on(), HEAD_ON_END),
        ("drop", drop_scene(), END),
    ] {
        let want = whole_run(&bodies, end);
        for k in 1..=4 {
            let got = split_run(&bodies, &[k, k], rule, end).0;
            assert_eq!(
                first_difference(&got, &want),
                None,
                "{name}, {k} parts each"
            );
        }
    }
}

/// One body of two parallel sheets (one mesh, two components) with self-contact, the
/// sheets closing at 2 m/s each: every hit is the body's own, which a view selects by
/// the self-contact rule (nodes within G, segments within 2G of the holder's elements
/// of that body; `partition::select`).
fn two_sheets() -> Vec<Body> {
    let (t, gap, v) = (0.002, 1e-4, 2.0);
    let sheet = |z: f64| {
        let mut m = plate(0.1, 0.1, 10, 10, ElementKind::Quad);
        m.transform(&nalgebra::Matrix3::identity(), Vec3::new(0.0, 0.0, z));
        m
    };
    let (mut m, b) = (sheet(0.0), sheet(t + gap));
    let n = m.nodes.len() as u32;
    m.nodes.extend(b.nodes.iter().copied());
    m.quads.extend(b.quads.iter().map(|q| q.map(|i| i + n)));
    let mut body = shell(0, &m, t);
    body.def_mut().self_contact = true;
    for (i, x) in body.state.v.iter_mut().enumerate() {
        *x = Vec3::new(0.0, 0.0, if i < n as usize { v } else { -v });
    }
    vec![body]
}

#[test]
fn a_self_contacting_body_in_parts_steps_bit_identically_to_the_whole_body() {
    let bodies = two_sheets();
    let end = 5e-4;
    let want = whole_run(&bodies, end);
    assert!(want.active >= 10, "the sheets touch: {} nodes", want.active);
    for k in 1..=4 {
        let (got, pushes, _) = split_run(&bodies, &[k], ViewRule::default(), end);
        assert_eq!(got.hashes.len(), want.hashes.len(), "{k} parts: steps");
        assert_eq!(
            first_difference(&got, &want),
            None,
            "{k} parts: x, v, w or dt"
        );
        let stats_differ = (0..want.contacts.len()).find(|&s| got.contacts[s] != want.contacts[s]);
        assert_eq!(stats_differ, None, "{k} parts: contact statistics");
        assert_eq!(pushes, want.pushes, "{k} parts: pushes booked");
    }
}
