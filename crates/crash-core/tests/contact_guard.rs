//! The tunnelling guard and the initial-penetration report.

mod contact_util;

use contact_util::*;
use crash_core::contact::{initial_penetrations, ContactConfig, ContactPass, Inside, PenaltyKind};
use crash_core::{Body, Fault, Run, RunConfig, Vec3};

fn fast_sphere_run(margin: f64, speed: f64) -> Result<Run, Fault> {
    let (r, t) = (0.1, 0.002);
    let s = sphere(
        0,
        r,
        t,
        3,
        Vec3::new(0.0, 0.0, r + 0.01),
        Vec3::new(0.0, 0.0, -speed),
    );
    let p = fixed_plate(1, 0.3, 10, t, 0.0);
    let cfg = ContactConfig {
        margin,
        ..Default::default()
    };
    let mut run = Run::new(
        group(vec![s, p], cfg),
        RunConfig {
            end_time: 1.0,
            ..Default::default()
        },
    )?;
    for _ in 0..10 {
        run.step()?;
    }
    Ok(run)
}

#[test]
fn node_crossing_the_margin_in_one_step_stops_the_run() {
    let (margin, speed) = (1e-4, 300.0);
    let err = fast_sphere_run(margin, speed).expect_err("must stop");
    println!("{err}");
    match err {
        Fault::Tunnelling {
            step,
            body,
            speed: s,
            distance,
            budget,
            ..
        } => {
            assert_eq!(step, 1);
            assert_eq!(body, 0);
            assert!((s - speed).abs() < 1e-6 * speed, "speed {s}");
            assert!(distance > budget);
            assert!((budget - 0.5 * margin).abs() < 1e-15);
        }
        other => panic!("expected tunnelling, got {other}"),
    }
    // the same sphere with a margin that covers its step runs on
    let run = fast_sphere_run(20.0 * margin, speed).expect("runs");
    let step = speed * run.dt0;
    println!(
        "step length {step:.3e} m, budget {:.3e} m",
        0.5 * 20.0 * margin
    );
    assert!(step > 0.5 * margin && step < 0.5 * 20.0 * margin);
}

#[test]
fn initial_penetrations_name_bodies_and_depth() {
    let (r, t, tp) = (0.1, 0.002, 0.004);
    let depth = 3e-4;
    // sphere pole sits `depth` inside the plate's contact surface
    let s = sphere(
        0,
        r,
        t,
        3,
        Vec3::new(0.0, 0.0, r + 0.5 * (t + tp) - depth),
        Vec3::zeros(),
    );
    let p = fixed_plate(7, 0.3, 10, tp, 0.0);
    let far = sphere(3, r, t, 2, Vec3::new(2.0, 0.0, 0.5), Vec3::zeros());
    let found = initial_penetrations(&[s.clone(), p.clone(), far], &ContactConfig::default());
    println!("{found:?}");
    // the sphere's pole node penetrates the plate (and the plate's centre node the
    // sphere's pole, reported as the reverse pass); the far sphere is not involved
    let hit = found
        .iter()
        .find(|q| q.node_body == 0 && q.segment_body == 7)
        .expect("reported");
    assert!((hit.depth - depth).abs() < 1e-12, "depth {}", hit.depth);
    let Inside::Node(node) = hit.at else {
        panic!("a node pass reports nodes: {hit:?}")
    };
    assert!(
        (s.state.x[node].z - s.state.x.iter().map(|q| q.z).fold(f64::INFINITY, f64::min)).abs()
            < 1e-15
    );
    assert!(found
        .iter()
        .all(|q| q.node_body != 3 && q.segment_body != 3));
    assert!(found
        .iter()
        .all(|q| q.nodes == 1 && (q.depth - depth).abs() < 1e-12));
    // moved clear: nothing to report
    let mut lifted = s.clone();
    for x in &mut lifted.state.x {
        x.z += 2.0 * depth;
    }
    assert!(initial_penetrations(&[lifted, p], &ContactConfig::default()).is_empty());
}

/// A coarse sphere whose lowest facet lies flat `lift` beyond contact distance of a
/// plate: every node is outside, the curved surface the segment pass presses with
/// bulges below the facet by about the facet's sagitta.
fn facet_down_sphere(lift: f64) -> (Body, f64) {
    let (r, t, level) = (0.03, 0.5e-3, 1);
    let mut m = crash_core::shapes::icosphere(r, level);
    let tri = m.tris[0];
    let centroid: Vec3 = tri.iter().map(|&n| m.nodes[n as usize]).sum::<Vec3>() / 3.0;
    let rot = nalgebra::Rotation3::rotation_between(&centroid, &-Vec3::z()).expect("not opposite");
    m.transform(rot.matrix(), Vec3::zeros());
    let low = m.nodes.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    // plate at z = 0 of thickness t: contact distance t
    m.transform(
        &nalgebra::Matrix3::identity(),
        Vec3::new(0.0, 0.0, t + lift - low),
    );
    let sagitta = r - (centroid.norm());
    (shell(0, &m, t), sagitta)
}

#[test]
fn a_curved_surface_reaching_into_a_body_where_no_node_does_is_an_initial_penetration_under_the_segment_pass(
) {
    let lift = 0.2e-3;
    let (s, sagitta) = facet_down_sphere(lift);
    let p = fixed_plate(1, 0.1, 20, 0.5e-3, 0.0);
    let nodes = ContactConfig::default();
    let segments = ContactConfig {
        pass: ContactPass::Segments,
        penalty: PenaltyKind::Soft,
        ..ContactConfig::default()
    };
    // the node passes see every node 0.2 mm clear
    assert!(initial_penetrations(&[s.clone(), p.clone()], &nodes).is_empty());
    let found = initial_penetrations(&[s.clone(), p.clone()], &segments);
    println!("sagitta {sagitta:.4e} m: {found:?}");
    // one entry: the pass searches the finer surface's points (here the plate's, 5 mm
    // quads under a level-1 sphere's facets) against the coarser one's curved surface
    assert_eq!(found.len(), 1, "{found:?}");
    let hit = &found[0];
    assert_eq!((hit.node_body, hit.segment_body), (1, 0), "{hit:?}");
    assert!(matches!(hit.at, Inside::Point { .. }), "{hit:?}");
    // the curved surface dips below the facet by less than the sphere's sagitta (the
    // bulge is the quadratic of the nodal normals, 0.4 of it at this facet's centroid)
    assert!(
        hit.depth > 0.2 * sagitta && hit.depth < sagitta - lift,
        "depth {:.4e}",
        hit.depth
    );
    // lifted past the bulge: nothing under either pass
    let (high, _) = facet_down_sphere(sagitta);
    let high = initial_penetrations(&[high, p], &segments);
    assert!(high.is_empty(), "{high:?}");
}
