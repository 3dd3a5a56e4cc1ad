//! Frictionless oblique impact on a fixed plate: a level-4 spherical shell (R 50 mm,
//! t 1 mm) thrown at 1 m/s down and 1 m/s across keeps its tangential velocity, gains no
//! rolling spin and rebounds with a normal restitution close to 1 and never above it
//! (docs/theory-contact.md, "Normal: smoothed over facets" and "Oblique impacts: where
//! the normal energy goes").

mod contact_util;

use contact_util::*;
use crash_core::contact::{ContactConfig, ContactPass};
use crash_core::{Body, Run, RunConfig, Vec3};

struct After {
    tangential: f64,
    restitution: f64,
    spin: Vec3,
    spin_scale: f64,
    balance: f64,
    /// Where the normal kinetic energy 1/2 m v_z0^2 went, as fractions of it: the gain
    /// in tangential kinetic energy of the centre of mass, in rigid rotation energy,
    /// the vibration kinetic energy (what the rigid motion does not carry), strain
    /// energy, and the work contact kept (the ball's contact energy after separation).
    tangential_ke: f64,
    spin_ke: f64,
    vibration: f64,
    strain: f64,
    contact: f64,
}

/// Kinetic energy of the rigid rotation about the centre of mass: 1/2 omega . L_c,
/// omega = I_c^-1 L_c with the body's inertia tensor (nodal masses and rotary inertias).
fn rigid_spin_energy(b: &Body) -> f64 {
    let xc = b.centre_of_mass();
    let lc = b.angular_momentum() - xc.cross(&b.linear_momentum());
    let mut i = nalgebra::Matrix3::zeros();
    for (k, x) in b.state.x.iter().enumerate() {
        let r = x - xc;
        i += (nalgebra::Matrix3::identity() * r.norm_squared() - r * r.transpose()) * b.def.mass[k]
            + nalgebra::Matrix3::identity() * b.def.inertia[k];
    }
    let w = i
        .try_inverse()
        .expect("a shell's inertia tensor is regular")
        * lc;
    0.5 * w.dot(&lc)
}

fn oblique(offset: Vec3, spin: Vec3, pass: ContactPass) -> After {
    let (r, t) = (0.05, 1e-3);
    let tp = 2e-3;
    let c0 = Vec3::new(offset.x, offset.y, r + 0.5 * (t + tp) + 1e-4);
    let v0 = Vec3::new(1.0, 0.0, -1.0);
    let mut s = sphere(0, r, t, 4, c0, v0);
    s.set_rigid_velocity(v0, spin, c0);
    let p = fixed_plate(1, 0.3, 60, tp, 0.0);
    let mut run = Run::new(
        group(
            vec![s, p],
            ContactConfig {
                pass,
                ..Default::default()
            },
        ),
        RunConfig {
            end_time: 1.5e-3,
            ..Default::default()
        },
    )
    .expect("start");
    let b = &run.group.bodies[0];
    let (l0, m) = (
        b.angular_momentum() - b.centre_of_mass().cross(&b.linear_momentum()),
        b.total_mass(),
    );
    let spin_ke0 = rigid_spin_energy(b);
    let mut last_contact = 0.0;
    run.run(|r| {
        if r.group.contact_stats().iter().any(|s| s.active_nodes > 0) {
            last_contact = r.time();
        }
    })
    .expect("runs");
    assert!(
        last_contact > 0.0 && last_contact < run.time(),
        "it bounced off"
    );
    let b = &run.group.bodies[0];
    let v = com_velocity(b);
    // spin about the centre of mass: L_c / I, I = 2/3 m R^2 of a thin sphere
    let lc = b.angular_momentum() - b.centre_of_mass().cross(&b.linear_momentum());
    let inertia = 2.0 / 3.0 * m * r * r;
    let e_n = 0.5 * m * v0.z * v0.z;
    let spin_ke = rigid_spin_energy(b);
    let report = &run.reports[0].energy;
    After {
        tangential_ke: 0.5 * m * (v.x * v.x + v.y * v.y - v0.x * v0.x) / e_n,
        spin_ke: (spin_ke - spin_ke0) / e_n,
        vibration: (b.kinetic_energy_now() - 0.5 * m * v.norm_squared() - spin_ke) / e_n,
        strain: (report.internal + report.hourglass) / e_n,
        contact: report.contact / e_n,
        tangential: v.x / v0.x,
        restitution: v.z / -v0.z,
        spin: (lc - l0) / inertia,
        // the rolling spin v_t / R the tangential change would mean
        spin_scale: v0.x / r,
        balance: run.ledger.max_error(),
    }
}

/// The three cases of issue 12: sliding with a plate node under the ball's pole, sliding
/// with no plate node under the ball, rolling without slip (spin 20 rad/s = v_t / R).
fn cases() -> [(&'static str, Vec3, Vec3); 3] {
    [
        (
            "sliding, plate node under the pole",
            Vec3::zeros(),
            Vec3::zeros(),
        ),
        (
            "sliding, no plate node under the ball",
            Vec3::new(0.0021, 0.0013, 0.0),
            Vec3::zeros(),
        ),
        ("rolling", Vec3::zeros(), Vec3::new(0.0, 20.0, 0.0)),
    ]
}

fn show(name: &str, a: &After) {
    println!(
        "{name}: v_t ratio {:.5}, e {:.5}, spin change {:?} rad/s ({:.2e} of v_t/R), balance {:.2e}",
        a.tangential,
        a.restitution,
        a.spin.as_slice(),
        a.spin.norm() / a.spin_scale,
        a.balance
    );
    println!(
        "   1 - e^2 = {:.4}: tangential KE {:.4}, spin KE {:.4}, vibration {:.4}, strain {:.4}, kept by contact {:.4}",
        1.0 - a.restitution * a.restitution,
        a.tangential_ke,
        a.spin_ke,
        a.vibration,
        a.strain,
        a.contact
    );
}

/// Sliding, no spin: a plate node lies under the ball's pole (the case that gained
/// +1.22 % tangential velocity and -0.31 rad/s of rolling spin with the closest-point
/// normal), and the same ball offset so that no plate node lies under it.
#[test]
fn sliding_oblique_impact_keeps_tangential_velocity_within_0_2_percent_and_gains_no_spin() {
    for (name, offset, spin) in &cases()[..2] {
        let a = oblique(*offset, *spin, ContactPass::Nodes);
        show(name, &a);
        assert!(
            (a.tangential - 1.0).abs() < 2e-3,
            "tangential {}",
            a.tangential
        );
        assert!(a.spin.norm() < 0.005 * a.spin_scale, "spin {:?}", a.spin);
        // never above 1; where a plate node lies under the pole the issue's "within 1 %
        // of 1" is not met (0.985: the smoothed force is not the gap's gradient, and
        // contact keeps 2.3 % of the normal kinetic energy; see the energy test below)
        assert!(
            a.restitution <= 1.0 && a.restitution > 0.98,
            "e {}",
            a.restitution
        );
        assert!(a.balance < 2e-4, "balance {}", a.balance);
    }
}

/// Rolling without slip (spin 20 rad/s = v_t / R): recorded, with looser bounds (see
/// docs/theory-contact.md: smoothing halves the spin change of the closest-point
/// normal, 0.43 -> 0.21 rad/s, but the tangential change grows from 0.01 % to 0.7 %).
#[test]
fn rolling_oblique_impact_keeps_tangential_velocity_within_1_percent() {
    let (name, offset, spin) = cases()[2];
    let a = oblique(offset, spin, ContactPass::Nodes);
    show(name, &a);
    assert!(
        (a.tangential - 1.0).abs() < 1e-2,
        "tangential {}",
        a.tangential
    );
    assert!(a.spin.norm() < 0.015 * a.spin_scale, "spin {:?}", a.spin);
    assert!(
        a.restitution <= 1.0 && a.restitution > 0.98,
        "e {}",
        a.restitution
    );
}

/// Where the normal kinetic energy goes: (1 - e^2) of it is the gain in tangential and
/// spin energy, the shell's vibration and strain energy and what contact kept, to the
/// run's energy balance (closure within 1e-3 of it); and the shell itself keeps under
/// 0.5 % as vibration and strain after separation in every case, so a restitution below
/// 0.99 is not the shell ringing (measured 0.36 % to 0.42 %), it is energy moved into
/// the tangential motion and spin, or kept by the contact forces' work.
#[test]
fn oblique_impacts_lose_normal_energy_to_named_sinks_not_to_shell_vibration() {
    for (name, offset, spin) in cases() {
        let a = oblique(offset, spin, ContactPass::Nodes);
        show(name, &a);
        let sinks = a.tangential_ke + a.spin_ke + a.vibration + a.strain + a.contact;
        let lost = 1.0 - a.restitution * a.restitution;
        assert!(
            (lost - sinks).abs() < 1e-3,
            "{name}: 1 - e^2 = {lost}, sinks {sinks}"
        );
        assert!(
            a.vibration + a.strain < 5e-3,
            "{name}: vibration {} + strain {}",
            a.vibration,
            a.strain
        );
    }
}

/// Issue 12, point 2, as stated: tangential velocity within 0.2 %, spin change under
/// 5e-3 of v_t/R, restitution in [0.99, 1], in all three cases, with the segment pass
/// (`contact.pass = segments`). The node passes miss it (pole case e 0.985; rolling
/// 1.0070, 1.1e-2, 0.983: the tests above); docs/theory-contact.md says why.
#[test]
fn oblique_impacts_meet_issue_12_bounds() {
    let mut misses = Vec::new();
    for (name, offset, spin) in cases() {
        let a = oblique(offset, spin, ContactPass::Segments);
        show(name, &a);
        let ok = (a.tangential - 1.0).abs() < 2e-3
            && a.spin.norm() < 5e-3 * a.spin_scale
            && (0.99..=1.0).contains(&a.restitution);
        if !ok {
            misses.push(name);
        }
    }
    assert!(misses.is_empty(), "outside the bounds: {misses:?}");
}

/// The segment pass's force is the exact gradient of its potential: after separation
/// the contact keeps (or gives) under 1e-4 of the normal kinetic energy in every case
/// (the node passes keep 2.3 % in the pole case), the sinks close 1 - e^2 within 1e-3,
/// and the energy balance holds.
#[test]
fn segment_pass_gives_back_the_work_of_contact() {
    for (name, offset, spin) in cases() {
        let a = oblique(offset, spin, ContactPass::Segments);
        show(name, &a);
        assert!(a.contact.abs() < 1e-4, "{name}: contact kept {}", a.contact);
        let sinks = a.tangential_ke + a.spin_ke + a.vibration + a.strain + a.contact;
        let lost = 1.0 - a.restitution * a.restitution;
        assert!(
            (lost - sinks).abs() < 1e-3,
            "{name}: 1 - e^2 = {lost}, sinks {sinks}"
        );
        assert!(a.balance < 2e-4, "{name}: balance {}", a.balance);
    }
}
