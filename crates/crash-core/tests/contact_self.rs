//! Self-contact: two sheets of one body (one mesh, two components) collide like two
//! bodies would; with self-contact off they pass through; a thick closed shell at rest
//! finds no contact with its own neighbourhood.

mod contact_util;

use contact_util::*;
use crash_core::contact::ContactConfig;
use crash_core::shapes::{plate, ElementKind};
use crash_core::{Body, Mesh, Run, RunConfig, Vec3};

const T: f64 = 0.002;
const GAP: f64 = 1e-4;
const V: f64 = 2.0;

fn sheet(z: f64) -> Mesh {
    let mut m = plate(0.1, 0.1, 10, 10, ElementKind::Quad);
    m.transform(&nalgebra::Matrix3::identity(), Vec3::new(0.0, 0.0, z));
    m
}

fn set_v(b: &mut Body, v: f64) {
    for x in &mut b.state.v {
        *x = Vec3::new(0.0, 0.0, v);
    }
}

/// Sheet velocities after 0.5 ms: (lower, upper) mean z velocity.
fn run(bodies: Vec<Body>, split: impl Fn(&Run) -> (f64, f64)) -> (f64, f64) {
    let cfg = ContactConfig {
        margin: 1e-3,
        ..Default::default()
    };
    let mut run = Run::new(
        group(bodies, cfg),
        RunConfig {
            end_time: 5e-4,
            ..Default::default()
        },
    )
    .expect("start");
    run.run(|_| {}).expect("run");
    split(&run)
}

#[test]
fn self_contact_between_two_sheets_of_one_body_matches_two_bodies() {
    let zt = T + GAP;
    // two bodies
    let mut lo = shell(0, &sheet(0.0), T);
    let mut hi = shell(1, &sheet(zt), T);
    set_v(&mut lo, V);
    set_v(&mut hi, -V);
    let two = run(vec![lo, hi], |r| {
        (
            com_velocity(&r.group.bodies[0]).z,
            com_velocity(&r.group.bodies[1]).z,
        )
    });
    // one body holding both sheets
    let (a, b) = (sheet(0.0), sheet(zt));
    let n = a.nodes.len() as u32;
    let mut m = a.clone();
    m.nodes.extend(b.nodes.iter().copied());
    m.quads.extend(b.quads.iter().map(|q| q.map(|i| i + n)));
    let mean_z = |r: &Run, range: std::ops::Range<usize>| {
        let b = &r.group.bodies[0];
        range
            .clone()
            .map(|i| b.state.v[i].z * b.def.mass[i])
            .sum::<f64>()
            / range.map(|i| b.def.mass[i]).sum::<f64>()
    };
    let one = |self_contact: bool| {
        let mut body = shell(0, &m, T);
        body.def_mut().self_contact = self_contact;
        for (i, v) in body.state.v.iter_mut().enumerate() {
            *v = Vec3::new(0.0, 0.0, if i < n as usize { V } else { -V });
        }
        run(vec![body], |r| {
            (
                mean_z(r, 0..n as usize),
                mean_z(r, n as usize..2 * n as usize),
            )
        })
    };
    let with = one(true);
    let without = one(false);
    println!("two bodies {two:?}, one body with self-contact {with:?}, without {without:?}");
    assert!(
        two.0 < -0.9 * V && two.1 > 0.9 * V,
        "the two bodies bounced"
    );
    assert!((with.0 - two.0).abs() < 1e-9 * V && (with.1 - two.1).abs() < 1e-9 * V);
    assert!(
        (without.0 - V).abs() < 1e-9 && (without.1 + V).abs() < 1e-9,
        "no self-contact: they pass"
    );
}

#[test]
fn thick_closed_shell_at_rest_has_no_self_contact() {
    // element edges ~13 mm, thickness 20 mm: second-ring segments are within contact
    // distance of a node from the start and must be excluded
    let mut s = sphere(0, 0.1, 0.02, 3, Vec3::zeros(), Vec3::zeros());
    s.def_mut().self_contact = true;
    let mut g = group(
        vec![s],
        ContactConfig {
            margin: 1e-3,
            ..Default::default()
        },
    );
    g.start().expect("start");
    let stats = g.contact_stats().to_vec();
    println!("{stats:?}");
    assert_eq!(stats.len(), 1, "the self pair is searched");
    assert_eq!((stats[0].a, stats[0].b), (0, 0));
    assert_eq!(stats[0].active_nodes, 0);
}
