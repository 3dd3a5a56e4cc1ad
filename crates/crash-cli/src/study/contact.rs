//! Verification cases with contact (steel shells R = 0.1 m, t = 1 mm): Reissner's
//! point-load stiffness, the bounce duration pi sqrt(m/k), two spheres head-on
//! (velocity exchange, momentum) and the energy balance of a sphere dropped on a plate.
//! Setups follow crates/crash-core/tests/contact_*.rs.

use super::build::{cap, com_velocity, fixed_plate, reissner_stiffness, shell, sphere};
use super::build::{sphere_edge, steel};
use super::ladder::{driver, measure, CaseError, Level, Measurement, Raw};
use crash_core::contact::ContactConfig;
use crash_core::{dof, Body, Group, Vec3, VelocityProgram};

const R: f64 = 0.1;
const T: f64 = 0.001;

fn group(bodies: Vec<Body>, margin: f64) -> Group {
    let mut g = Group::new(bodies, Vec3::zeros());
    g.contact = ContactConfig {
        margin,
        ..Default::default()
    };
    g
}

/// A clamped 25-degree cap (R/t = 100) pressed slowly (0.2 m/s, mass-damped) by a rigid
/// plane moving up; the least-squares chord slope of force over pole deflection for
/// w <= t/2 against Reissner's k = 4 E t^2 / (R sqrt(3(1-nu^2))).
pub fn reissner(level: Level) -> Result<Measurement, CaseError> {
    let k = reissner_stiffness(&steel(), R, T);
    measure(level, k, || {
        let tp = 0.001;
        let (mesh, rim) = cap(R, level.mesh, 25f64.to_radians());
        let mut c = shell(0, &mesh, steel(), T)?;
        for &n in &rim {
            c.fix(n, dof::ALL);
        }
        c.def_mut().mass_damping = 5000.0;
        let pole = (0..c.state.x.len())
            .min_by(|&a, &b| c.state.x[a].z.total_cmp(&c.state.x[b].z))
            .unwrap_or(0);
        let (gap0, vp) = (5e-5, 0.2);
        let mut p = fixed_plate(1, 0.04, 8, tp, -R - 0.5 * (T + tp) - gap0)?;
        let all: Vec<usize> = (0..p.state.x.len()).collect();
        p.prescribe(
            &all,
            VelocityProgram {
                displacement: false,
                velocity: Vec3::new(0.0, 0.0, vp),
                angular: Vec3::zeros(),
                ramp: 2e-4,
                curve: crash_core::NO_CURVE,
            },
        );
        let elements = c.element_count() + p.element_count();
        let end = 2e-4 / 2.0 + (gap0 + 0.52 * T) / vp;
        let mut run = driver(group(vec![c, p], 1e-3), end, level.safety)?;
        let z0 = run.bodies()[0].state.x[pole].z;
        let mut curve = Vec::new();
        run.run(|r| {
            let w = r.bodies[0].state.x[pole].z - z0;
            let f = r.contact_stats().first().map_or(0.0, |s| s.normal_force);
            curve.push((w, f));
        })?;
        let below: Vec<(f64, f64)> = curve
            .into_iter()
            .filter(|(w, _)| *w > 0.0 && *w <= 0.5 * T)
            .collect();
        let chord = below.iter().map(|(w, f)| w * f).sum::<f64>()
            / below.iter().map(|(w, _)| w * w).sum::<f64>();
        Ok(Raw {
            h: sphere_edge(R, level.mesh),
            elements,
            steps: run.clock.step,
            value: chord,
            notes: vec![],
        })
    })
}

/// A sphere (R/t = 100) at 0.5 m/s onto a fixed plate, in the linear range: contact
/// lasts pi sqrt(m / k) with Reissner's k and the mesh's mass m.
pub fn bounce(level: Level) -> Result<Measurement, CaseError> {
    let (tp, gap0, v0) = (0.001, 2e-5, 0.5);
    let s = sphere(
        0,
        (R, T),
        level.mesh,
        steel(),
        Vec3::new(0.0, 0.0, R + 0.5 * (T + tp) + gap0),
        Vec3::new(0.0, 0.0, -v0),
    )?;
    let m = s.total_mass();
    let k = reissner_stiffness(&steel(), R, T);
    let expected = std::f64::consts::PI * (m / k).sqrt();
    measure(level, expected, || {
        let p = fixed_plate(1, 0.1, 10, tp, 0.0)?;
        let elements = s.element_count() + p.element_count();
        let mut run = driver(
            group(vec![s, p], 5e-4),
            gap0 / v0 + 1.3 * expected,
            level.safety,
        )?;
        let (mut first, mut last) = (None, 0.0);
        run.run(|r| {
            if let Some(st) = r.contact_stats().first() {
                if st.active_nodes > 0 {
                    first.get_or_insert(r.time());
                    last = r.time();
                }
            }
        })?;
        let duration = first.map_or(f64::NAN, |f| last - f);
        let rebound = com_velocity(run.bodies()[0]).z / v0;
        Ok(Raw {
            h: sphere_edge(R, level.mesh),
            elements,
            steps: run.clock.step,
            value: duration,
            notes: vec![
                ("restitution".into(), rebound),
                ("max energy error".into(), run.max_energy_error),
            ],
        })
    })
}

/// Two equal spheres head-on at +-1 m/s: they exchange velocities (value: the velocity
/// of the left one after, over minus its velocity before; reference 1) and keep the
/// total momentum (note: largest |sum p| / (m v0) over the run).
pub fn spheres_head_on(level: Level) -> Result<Measurement, CaseError> {
    measure(level, 1.0, || {
        let v0 = 1.0;
        let x0 = R + 0.5 * T + 1e-4;
        let a = sphere(
            0,
            (R, T),
            level.mesh,
            steel(),
            Vec3::new(-x0, 0.0, 0.0),
            Vec3::new(v0, 0.0, 0.0),
        )?;
        let b = sphere(
            1,
            (R, T),
            level.mesh,
            steel(),
            Vec3::new(x0, 0.0, 0.0),
            Vec3::new(-v0, 0.0, 0.0),
        )?;
        let p_scale = a.total_mass() * v0;
        let elements = a.element_count() + b.element_count();
        let mut run = driver(group(vec![a, b], 1e-3), 1.6e-3, level.safety)?;
        let mut drift: f64 = 0.0;
        run.run(|r| {
            let p: Vec3 = r.bodies.iter().map(|b| b.linear_momentum()).sum();
            drift = drift.max(p.norm() / p_scale);
        })?;
        let va = com_velocity(run.bodies()[0]);
        Ok(Raw {
            h: sphere_edge(R, level.mesh),
            elements,
            steps: run.clock.step,
            value: -va.x / v0,
            notes: vec![
                ("momentum drift".into(), drift),
                ("max energy error".into(), run.max_energy_error),
            ],
        })
    })
}

/// A sphere at 2 m/s onto a fixed 0.3 m plate (the paper's first benchmark, small): the
/// largest energy-balance error of the run (reference 0).
pub fn sphere_on_plate(level: Level) -> Result<Measurement, CaseError> {
    measure(level, 0.0, || {
        let (tp, gap0, v0) = (0.002, 2e-4, 2.0);
        let s = sphere(
            0,
            (R, T),
            level.mesh,
            steel(),
            Vec3::new(0.0, 0.0, R + 0.5 * (T + tp) + gap0),
            Vec3::new(0.0, 0.0, -v0),
        )?;
        let p = fixed_plate(1, 0.3, 20, tp, 0.0)?;
        let elements = s.element_count() + p.element_count();
        let mut run = driver(group(vec![s, p], 1e-3), 2.5e-3, level.safety)?;
        let mut pen: f64 = 0.0;
        run.run(|r| {
            for st in r.contact_stats() {
                pen = pen.max(st.max_penetration_ratio);
            }
        })?;
        let rebound = com_velocity(run.bodies()[0]).z / v0;
        Ok(Raw {
            h: sphere_edge(R, level.mesh),
            elements,
            steps: run.clock.step,
            value: run.max_energy_error,
            notes: vec![
                ("restitution".into(), rebound),
                ("max penetration/t".into(), pen),
            ],
        })
    })
}
