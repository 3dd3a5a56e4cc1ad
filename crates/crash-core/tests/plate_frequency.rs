//! Natural frequencies of simply supported plates, measured from free vibration:
//! NAFEMS FV52 (thick, Mindlin: f1 = 45.897 Hz) and a thin plate against Kirchhoff.
//! Each prints its refinement ladder (elements, steps, wall time, error) and the
//! observed order of convergence.

mod common;

use common::*;
use crash_core::body::dof;
use crash_core::shapes::ElementKind;
use crash_core::{Group, Material, Run, RunConfig, Vec3};
use std::f64::consts::PI;
use std::time::Instant;

/// Simply supported square plate (side a, hard support: w = 0 and the twist rotation
/// along each edge fixed, in-plane translations of the edges fixed), excited in its
/// (1,1) shape; returns the frequency from the zero crossings of the centre deflection,
/// the element count and the step count.
fn first_frequency(
    kind: ElementKind,
    n: usize,
    a: f64,
    t: f64,
    mat: Material,
    periods: f64,
    f_guess: f64,
) -> (f64, usize, u64) {
    let mut b = corner_plate(a, a, n, n, kind, mat, t);
    let tol = 1e-9 * a;
    for i in 0..b.state.x.len() {
        let p = b.def.x0[i];
        if p.x.abs() < tol || (p.x - a).abs() < tol {
            b.fix(i, dof::X | dof::Y | dof::Z | dof::RX);
        }
        if p.y.abs() < tol || (p.y - a).abs() < tol {
            b.fix(i, dof::X | dof::Y | dof::Z | dof::RY);
        }
        let v = 1e-3 * (PI * p.x / a).sin() * (PI * p.y / a).sin();
        b.state.v[i] = Vec3::new(0.0, 0.0, v);
    }
    let centre = (0..b.state.x.len())
        .min_by(|&i, &j| {
            let d = |k: usize| (b.def.x0[k] - Vec3::new(a / 2.0, a / 2.0, 0.0)).norm();
            d(i).total_cmp(&d(j))
        })
        .expect("nodes");
    let elements = b.element_count();
    let mut run = Run::new(
        Group::new(vec![b], Vec3::zeros()),
        RunConfig {
            end_time: periods / f_guess,
            ..Default::default()
        },
    )
    .expect("start");
    let mut crossings = Vec::new();
    let mut prev = (0.0, 0.0);
    run.run(|r| {
        let w = r.group.bodies[0].state.x[centre].z;
        let time = r.time();
        if prev.0 > 0.0 && prev.1 * w < 0.0 {
            crossings.push(prev.0 + prev.1 / (prev.1 - w) * (time - prev.0));
        }
        prev = (time, w);
    })
    .expect("run");
    let half_periods = (crossings.len() - 1) as f64;
    let f = half_periods / (2.0 * (crossings[crossings.len() - 1] - crossings[0]));
    (f, elements, run.clock.step)
}

fn ladder(
    name: &str,
    kind: ElementKind,
    a: f64,
    t: f64,
    mat: Material,
    reference: f64,
    ns: &[usize],
) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    println!("{name} {kind:?}: reference {reference:.4} Hz");
    println!(
        "  {:>6} {:>8} {:>8} {:>10} {:>10} {:>9}",
        "n", "elements", "steps", "wall [s]", "f [Hz]", "error"
    );
    for &n in ns {
        let start = Instant::now();
        let (f, elements, steps) = first_frequency(kind, n, a, t, mat, 4.0, reference);
        let err = (f - reference) / reference;
        println!(
            "  {n:>6} {elements:>8} {steps:>8} {:>10.3} {f:>10.4} {:>8.3}%",
            start.elapsed().as_secs_f64(),
            100.0 * err
        );
        out.push((a / n as f64, err.abs()));
    }
    let orders = orders(&out);
    println!(
        "  observed orders of convergence: {:?}",
        orders.iter().map(|o| format!("{o:.2}")).collect::<Vec<_>>()
    );
    out
}

#[test]
fn nafems_fv52_first_frequency_within_two_percent() {
    let mat = Material::new(8000.0, 200e9, 0.3, 0.0).expect("valid");
    for kind in kinds() {
        let l = ladder("FV52", kind, 10.0, 1.0, mat, 45.897, &[4, 8, 16, 32]);
        let finest = l.last().expect("ladder").1;
        assert!(finest < 0.02, "{kind:?}: {finest}");
    }
}

#[test]
fn thin_plate_first_frequency_matches_kirchhoff_within_two_percent() {
    let mat = steel();
    let (a, t): (f64, f64) = (1.0, 0.01);
    let d = mat.young * t.powi(3) / (12.0 * (1.0 - mat.poisson.powi(2)));
    let kirchhoff = PI / 2.0 * (2.0 / (a * a)) * (d / (mat.density * t)).sqrt();
    for kind in kinds() {
        let l = ladder("thin SS plate", kind, a, t, mat, kirchhoff, &[4, 8, 16, 32]);
        let finest = l.last().expect("ladder").1;
        assert!(finest < 0.02, "{kind:?}: {finest}");
    }
}
