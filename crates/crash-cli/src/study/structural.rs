//! Verification cases without contact: plate frequencies (NAFEMS FV52, thin plate
//! against Kirchhoff), cantilever tip deflection, membrane wave speed and rigid-body
//! rotation. Setups follow crates/crash-core/tests/{plate_frequency, cantilever,
//! wave_speed, rigid_body}.rs.

use super::build::{corner_plate, nearest, nodes_at, steel};
use super::ladder::{driver, group, measure, CaseError, Level, Measurement, Raw};
use crash_core::shapes::{plate, ElementKind};
use crash_core::{dof, Material, NodalLoad, Vec3, VelocityProgram};
use std::f64::consts::PI;

/// Simply supported square plate (w = 0 and the twist rotation along each edge held,
/// in-plane translations of the edges held), started in its (1,1) shape; the frequency
/// comes from the zero crossings of the centre deflection over `periods` periods.
fn plate_frequency(
    kind: ElementKind,
    level: Level,
    (a, t): (f64, f64),
    mat: Material,
    f_guess: f64,
) -> Result<Raw, CaseError> {
    let n = level.mesh as usize;
    let mut b = corner_plate(a, a, (n, n), kind, mat, t)?;
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
    let centre = nearest(&b, Vec3::new(a / 2.0, a / 2.0, 0.0));
    let elements = b.element_count();
    let mut run = driver(group(vec![b]), 4.0 / f_guess, level.safety)?;
    let mut crossings = Vec::new();
    let mut prev = (0.0, 0.0);
    run.run(|r| {
        let w = r.bodies[0].state.x[centre].z;
        let time = r.time();
        if prev.0 > 0.0 && prev.1 * w < 0.0 {
            crossings.push(prev.0 + prev.1 / (prev.1 - w) * (time - prev.0));
        }
        prev = (time, w);
    })?;
    let f = match (crossings.first(), crossings.last()) {
        (Some(first), Some(last)) if crossings.len() > 1 => {
            (crossings.len() - 1) as f64 / (2.0 * (last - first))
        }
        _ => f64::NAN,
    };
    Ok(Raw {
        h: a / n as f64,
        elements,
        steps: run.clock.step,
        value: f,
        notes: vec![],
    })
}

/// NAFEMS FV52: thick simply supported plate, L = 10 m, t = 1 m; f1 = 45.897 Hz.
pub const FV52_HZ: f64 = 45.897;

pub fn fv52(kind: ElementKind, level: Level) -> Result<Measurement, CaseError> {
    let mat = Material {
        density: 8000.0,
        young: 200e9,
        poisson: 0.3,
        kelvin: 0.0,
    };
    measure(level, FV52_HZ, || {
        plate_frequency(kind, level, (10.0, 1.0), mat, FV52_HZ)
    })
}

/// Kirchhoff f11 of a simply supported square steel plate a = 1 m, t = 10 mm.
pub fn kirchhoff_f11() -> f64 {
    let mat = steel();
    let (a, t): (f64, f64) = (1.0, 0.01);
    let d = mat.young * t.powi(3) / (12.0 * (1.0 - mat.poisson.powi(2)));
    PI / 2.0 * (2.0 / (a * a)) * (d / (mat.density * t)).sqrt()
}

pub fn thin_plate(kind: ElementKind, level: Level) -> Result<Measurement, CaseError> {
    let f = kirchhoff_f11();
    measure(level, f, || {
        plate_frequency(kind, level, (1.0, 0.01), steel(), f)
    })
}

/// Cantilever strip L x B x T, nu = 0 (a strip of any width bends like a beam).
const L: f64 = 1.0;
const B: f64 = 0.1;
const T: f64 = 0.01;

/// Tip deflection under a small end load P = 1 N: beam theory P L^3 / (3 E I). The
/// load is ramped over 0.05 s and the strip critically mass-damped in its first mode
/// (dynamic relaxation), measured at 0.4 s (residual of the transient ~1e-6).
pub fn cantilever(kind: ElementKind, level: Level) -> Result<Measurement, CaseError> {
    let e = 200e9;
    let inertia = B * T.powi(3) / 12.0;
    let p = 1.0;
    let exact = p * L.powi(3) / (3.0 * e * inertia);
    measure(level, exact, || {
        let nx = level.mesh as usize;
        let ny = (nx / 10).max(1);
        let mat = Material {
            density: 7800.0,
            young: e,
            poisson: 0.0,
            kelvin: 0.0,
        };
        let mut b = corner_plate(L, B, (nx, ny), kind, mat, T)?;
        for n in nodes_at(&b, 0, 0.0, 1e-9) {
            b.fix(n, dof::ALL);
        }
        let omega1 = 1.875f64.powi(2) * (e * inertia / (7800.0 * B * T)).sqrt() / (L * L);
        b.def_mut().mass_damping = 2.0 * omega1;
        let mut tip = nodes_at(&b, 0, L, 1e-9);
        tip.sort_by(|&i, &j| b.def.x0[i].y.total_cmp(&b.def.x0[j].y));
        let segs = tip.len() - 1;
        for (k, &node) in tip.iter().enumerate() {
            let w = if k == 0 || k == segs { 0.5 } else { 1.0 } / segs as f64;
            b.add_load(NodalLoad {
                node: node as u32,
                force: Vec3::new(0.0, 0.0, -p * w),
                moment: Vec3::zeros(),
                t0: 0.0,
                t1: 0.05,
                curve: crash_core::NO_CURVE,
            });
        }
        let elements = b.element_count();
        let mut run = driver(group(vec![b]), 0.4, level.safety)?;
        run.run(|_| {})?;
        let b = &run.bodies()[0];
        let w = -tip
            .iter()
            .map(|&i| b.state.x[i].z - b.def.x0[i].z)
            .sum::<f64>()
            / tip.len() as f64;
        Ok(Raw {
            h: L / nx as f64,
            elements,
            steps: run.clock.step,
            value: w,
            notes: vec![],
        })
    })
}

/// Time at which the history first exceeds `level` (linear interpolation).
fn arrival(history: &[(f64, f64)], level: f64) -> Option<f64> {
    history
        .windows(2)
        .find(|w| w[0].1 < level && w[1].1 >= level)
        .map(|w| w[0].0 + (level - w[0].1) / (w[1].1 - w[0].1) * (w[1].0 - w[0].0))
}

/// Membrane wave speed c = sqrt(E / (rho (1 - nu^2))) along a laterally constrained
/// steel strip 1 m x 20 mm: a velocity step at x = 0, front arrival (half the imposed
/// velocity) timed between x = 0.3 and x = 0.7.
pub fn wave_speed(kind: ElementKind, level: Level) -> Result<Measurement, CaseError> {
    let mat = steel();
    let exact = mat.wave_speed();
    measure(level, exact, || {
        let nx = level.mesh as usize;
        let ny = (nx / 50).max(1);
        let mut b = corner_plate(1.0, 0.02, (nx, ny), kind, mat, 0.002)?;
        for i in 0..b.state.x.len() {
            b.fix(i, dof::Y | dof::Z | dof::ROTATIONS);
        }
        let end = nodes_at(&b, 0, 0.0, 1e-9);
        b.prescribe(
            &end,
            VelocityProgram {
                displacement: false,
                velocity: Vec3::new(1.0, 0.0, 0.0),
                angular: Vec3::zeros(),
                ramp: 0.0,
                curve: crash_core::NO_CURVE,
            },
        );
        let probes = [0.3, 0.7];
        let tol = 0.25 / nx as f64;
        let sets: Vec<Vec<usize>> = probes.iter().map(|&x| nodes_at(&b, 0, x, tol)).collect();
        let elements = b.element_count();
        let mut hist = vec![Vec::new(); 2];
        let mut run = driver(group(vec![b]), 0.9 / exact, level.safety)?;
        run.run(|r| {
            let b = &r.bodies[0];
            for (h, set) in hist.iter_mut().zip(&sets) {
                let v = set.iter().map(|&i| b.state.v[i].x).sum::<f64>() / set.len().max(1) as f64;
                h.push((r.time() - 0.5 * r.clock.last_dt, v));
            }
        })?;
        let c = match (arrival(&hist[0], 0.5), arrival(&hist[1], 0.5)) {
            (Some(t1), Some(t2)) => (probes[1] - probes[0]) / (t2 - t1),
            _ => f64::NAN,
        };
        Ok(Raw {
            h: 1.0 / nx as f64,
            elements,
            steps: run.clock.step,
            value: c,
            notes: vec![],
        })
    })
}

/// A free plate 0.1 x 0.1 m, tilted, translating and spinning one full turn about the
/// in-plane diagonal (a principal axis): the largest (E_int + E_hg) / E_kin is the
/// spurious strain energy of the element under large rotation (reference 0; the real
/// centrifugal part is ~2e-10 at Omega R = 0.14 m/s).
pub fn rigid_rotation(kind: ElementKind, level: Level) -> Result<Measurement, CaseError> {
    measure(level, 0.0, || {
        let n = level.mesh as usize;
        let mut m = plate(0.1, 0.1, n, n, kind);
        let tilt = nalgebra::Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vec3::new(1.0, -2.0, 0.5)),
            0.7,
        );
        let centre = Vec3::new(0.3, -0.2, 1.0);
        m.transform(tilt.matrix(), centre);
        let mut b = super::build::body(0, &m, steel(), 0.002)?;
        let omega = tilt * Vec3::new(1.0, 1.0, 0.0).normalize() * 2.0;
        b.set_rigid_velocity(Vec3::new(0.1, -0.05, 0.2), omega, centre);
        let l0 = b.angular_momentum();
        let elements = b.element_count();
        let end = std::f64::consts::TAU / omega.norm();
        let mut run = driver(group(vec![b]), end, level.safety)?;
        let mut worst = 0.0f64;
        run.run(|r| {
            let e = r.bodies[0].state.energy;
            worst = worst.max((e.internal.abs() + e.hourglass.abs()) / e.kinetic);
        })?;
        let dl = (run.bodies()[0].angular_momentum() - l0).norm() / l0.norm();
        Ok(Raw {
            h: 0.1 / n as f64,
            elements,
            steps: run.clock.step,
            value: worst,
            notes: vec![("|dL|/|L|".into(), dl)],
        })
    })
}
