//! Shared scene builders of the contact tests (steel shells, SI units).
#![allow(dead_code)]

use crash_core::contact::ContactConfig;
use crash_core::shapes::{icosphere, plate, ElementKind};
use crash_core::{dof, Body, Group, Material, Mesh, Section, Stabilization, Vec3};

pub fn steel() -> Material {
    Material::steel()
}

pub fn shell(id: u32, mesh: &Mesh, t: f64) -> Body {
    let mut b = Body::new(
        id,
        &format!("b{id}"),
        mesh,
        Section::new(steel(), t),
        Stabilization::default(),
    )
    .expect("valid body");
    b.def_mut().contact = true;
    b
}

/// Icosphere shell of radius r at `centre`, moving rigidly with `v`.
pub fn sphere(id: u32, r: f64, t: f64, level: u32, centre: Vec3, v: Vec3) -> Body {
    let mut m = icosphere(r, level);
    m.transform(&nalgebra::Matrix3::identity(), centre);
    let mut b = shell(id, &m, t);
    b.set_rigid_velocity(v, Vec3::zeros(), centre);
    b
}

/// Square plate lx x lx in the plane z = z0, n x n quads, every DOF held (kinematic).
/// Two spheres (ids 0 and 1) on the x axis, `gap` apart at their mid-surfaces' closest
/// points beyond contact (t/2 each side), closing head-on at `v0` each.
#[allow(dead_code)] // not every test file uses every helper
pub fn head_on_pair(r: f64, t: f64, level: u32, gap: f64, v0: f64) -> (Body, Body) {
    let x0 = r + 0.5 * t + gap;
    (
        sphere(
            0,
            r,
            t,
            level,
            Vec3::new(-x0, 0.0, 0.0),
            Vec3::new(v0, 0.0, 0.0),
        ),
        sphere(
            1,
            r,
            t,
            level,
            Vec3::new(x0, 0.0, 0.0),
            Vec3::new(-v0, 0.0, 0.0),
        ),
    )
}

pub fn fixed_plate(id: u32, lx: f64, n: usize, t: f64, z0: f64) -> Body {
    let mut m = plate(lx, lx, n, n, ElementKind::Quad);
    m.transform(&nalgebra::Matrix3::identity(), Vec3::new(0.0, 0.0, z0));
    let mut b = shell(id, &m, t);
    for i in 0..b.state.x.len() {
        b.fix(i, dof::ALL);
    }
    b
}

pub fn group(bodies: Vec<Body>, contact: ContactConfig) -> Group {
    let mut g = Group::new(bodies, Vec3::zeros());
    g.contact = contact;
    g
}

/// Velocity of the centre of mass.
pub fn com_velocity(b: &Body) -> Vec3 {
    b.linear_momentum() / b.total_mass()
}

pub fn total_momentum(g: &Group) -> Vec3 {
    g.bodies.iter().map(|b| b.linear_momentum()).sum()
}

pub fn total_angular_momentum(g: &Group) -> Vec3 {
    g.bodies.iter().map(|b| b.angular_momentum()).sum()
}

#[allow(unused_imports)]
pub use crash_core::shapes::spherical_cap as cap;

/// Reissner's point-load stiffness of a thin spherical shell: 4 E t^2 / (R sqrt(3(1-nu^2))).
pub fn reissner_stiffness(r: f64, t: f64) -> f64 {
    let m = steel();
    4.0 * m.young * t * t / (r * (3.0 * (1.0 - m.poisson * m.poisson)).sqrt())
}

/// Least-squares slope of y over x.
pub fn slope(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / n, sy / n);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (x, y) in pts {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
    }
    sxy / sxx
}
