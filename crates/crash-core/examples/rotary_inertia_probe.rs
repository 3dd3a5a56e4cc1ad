//! The two quad runs that bound the nodal rotary-inertia factor f (docs/theory.md,
//! sections 3 and 8), with f given on the command line instead of `ROT_INERTIA_QUAD`:
//!
//! `rotary_inertia_probe precession F [safety]`: the free 2 x 2 quad plate of
//! tests/energy_hold.rs (0.1 m, steel, t = 2 mm) spinning at 2 rad/s about a
//! non-principal axis for 10 turns; prints the largest energy-balance error.
//!
//! `rotary_inertia_probe rollup F [ny] [moment factor] [end]`: the roll-up cantilever of
//! tests/cantilever.rs (40 x ny quads, default 2; end moment factor x 2 pi E I / L,
//! default 1, ramped over 0.6 s; end time default 1 s); prints the tip's distance to the
//! clamped end, the kinetic and hourglass energy and the energy-balance error every 0.1 s.
//! Ablations (docs/theory.md section 8): env HG_M, HG_W, HG_R scale the membrane, w and
//! rotational hourglass coefficients, SAFETY sets the step's safety factor.

use crash_core::body::dof;
use crash_core::shapes::{plate, ElementKind};
use crash_core::{Body, Group, Material, NodalLoad, Run, RunConfig, Section, Stabilization, Vec3};

/// Replace the nodal rotary inertia of a quad body by the rule of docs/theory.md
/// section 3 with area factor `f`.
fn set_quad_factor(b: &mut Body, f: f64) {
    let (rho, t) = (b.def.section.material.density, b.def.section.thickness);
    let quads = b.def.quads.clone();
    let d = b.def_mut();
    d.inertia.iter_mut().for_each(|i| *i = 0.0);
    for e in &quads {
        let m = rho * t * e.area0 / 4.0;
        for &n in &e.nodes {
            d.inertia[n as usize] += m * (t * t / 12.0).max(f * e.area0);
        }
    }
}

fn arg(a: &[String], i: usize, default: f64) -> f64 {
    a.get(i).and_then(|s| s.parse().ok()).unwrap_or(default)
}

fn precession(f: f64, safety: f64) {
    let m = plate(0.1, 0.1, 2, 2, ElementKind::Quad);
    let sec = Section::new(Material::steel(), 0.002);
    let mut b = Body::new(0, "plate", &m, sec, Stabilization::default()).expect("valid body");
    set_quad_factor(&mut b, f);
    let omega = Vec3::new(0.3, 0.5, 1.0).normalize() * 2.0;
    b.set_rigid_velocity(Vec3::zeros(), omega, Vec3::zeros());
    let end = 10.0 * std::f64::consts::TAU / omega.norm();
    let cfg = RunConfig {
        end_time: end,
        safety,
        ..Default::default()
    };
    let mut run = Run::new(Group::new(vec![b], Vec3::zeros()), cfg).expect("start");
    run.run(|_| {}).expect("run");
    println!(
        "precession, f = {f}, safety {safety}: {} steps, energy-balance error {:.3e}",
        run.clock.step,
        run.ledger.max_error()
    );
}

fn rollup(f: f64, ny: usize, factor: f64, end: f64) {
    let (l, w, t, e) = (1.0, 0.1, 0.01, 200e9);
    let i2 = w * t * t * t / 12.0;
    let moment = factor * std::f64::consts::TAU * e * i2 / l;
    let omega1 = 1.875f64.powi(2) * (e * i2 / (7800.0 * w * t)).sqrt() / (l * l);
    let mut m = plate(l, w, 40, ny, ElementKind::Quad);
    m.transform(
        &nalgebra::Matrix3::identity(),
        Vec3::new(l / 2.0, w / 2.0, 0.0),
    );
    let mat = Material::new(7800.0, e, 0.0, 0.0).expect("valid");
    let sec = Section::new(mat, t);
    // Ablation knobs (env): HG_M, HG_W, HG_R scale the hourglass coefficients, SAFETY the step.
    let knob = |k: &str, d: f64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let mut stab = Stabilization::default();
    stab.hourglass_membrane *= knob("HG_M", 1.0);
    stab.hourglass_w *= knob("HG_W", 1.0);
    stab.hourglass_rotation *= knob("HG_R", 1.0);
    let mut b = Body::new(0, "strip", &m, sec, stab).expect("valid body");
    set_quad_factor(&mut b, f);
    b.def_mut().mass_damping = 2.0 * omega1;
    let at = |b: &Body, x: f64| -> Vec<usize> {
        (0..b.def.x0.len())
            .filter(|&i| (b.def.x0[i].x - x).abs() < 1e-9)
            .collect()
    };
    for n in at(&b, 0.0) {
        b.fix(n, dof::ALL);
    }
    let mut tip = at(&b, l);
    tip.sort_by(|&i, &j| b.def.x0[i].y.total_cmp(&b.def.x0[j].y));
    let last = tip.len() - 1;
    for (k, &node) in tip.iter().enumerate() {
        let share = if k == 0 || k == last { 0.5 } else { 1.0 } / last as f64;
        b.add_load(NodalLoad {
            node: node as u32,
            force: Vec3::zeros(),
            moment: Vec3::new(0.0, -moment * share, 0.0),
            t0: 0.0,
            t1: 0.6,
            curve: crash_core::NO_CURVE,
        });
    }
    let cfg = RunConfig {
        end_time: end,
        safety: knob("SAFETY", RunConfig::default().safety),
        ..Default::default()
    };
    let mut run = Run::new(Group::new(vec![b], Vec3::zeros()), cfg).expect("start");
    let mut next = 0.1;
    let report = |r: &Run| {
        let b = &r.group.bodies[0];
        let p = tip.iter().map(|&i| b.state.x[i]).sum::<Vec3>() / tip.len() as f64;
        let gap = (p - Vec3::new(0.0, w / 2.0, 0.0)).norm();
        let en = &b.state.energy;
        println!(
            "rollup, f = {f}, 40 x {ny}, moment x {factor}: t {:.2} s, tip {gap:.4} m from the root, kinetic {:.3e} J, hourglass {:.3e} J, balance error {:.1e}",
            r.time(),
            en.kinetic,
            en.hourglass,
            r.ledger.max_error()
        );
    };
    // FOLLOWER=1: the moment's axis follows the tip's width line (a follower moment; the
    // dead one keeps the global y axis, the same only while the roll-up stays planar).
    let follower = knob("FOLLOWER", 0.0) > 0.0;
    let (lo, hi) = (tip[0], tip[last]);
    let outcome = (|| -> Result<(), crash_core::Fault> {
        while !run.finished() {
            run.step()?;
            if follower {
                let body = &mut run.group.bodies[0];
                let axis = (body.state.x[hi] - body.state.x[lo]).normalize();
                for ld in body.def_mut().loads.iter_mut() {
                    ld.moment = -ld.moment.norm() * axis;
                }
            }
            if run.time() >= next - 1e-12 {
                next += 0.1;
                report(&run);
            }
        }
        Ok(())
    })();
    if let Err(fault) = outcome {
        println!("rollup, f = {f}, 40 x {ny}, moment x {factor}: stopped: {fault}");
    }
}

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let f = arg(&a, 1, crash_core::body::ROT_INERTIA_QUAD);
    match a.first().map(String::as_str) {
        Some("precession") => precession(f, arg(&a, 2, 0.9)),
        Some("rollup") => rollup(
            f,
            arg(&a, 2, 2.0) as usize,
            arg(&a, 3, 1.0),
            arg(&a, 4, 1.0),
        ),
        _ => eprintln!("usage: rotary_inertia_probe precession|rollup F [...] (see the source)"),
    }
}
