//! Shared builders for the physics tests.
#![allow(dead_code)]

use crash_core::shapes::{plate, ElementKind};
use crash_core::{dof, Body, Material, Mesh, Section, Stabilization, Vec3, VelocityProgram};

pub fn steel() -> Material {
    Material::steel()
}

pub fn body(mesh: &crash_core::Mesh, mat: Material, t: f64) -> Body {
    Body::new(0, "b", mesh, Section::new(mat, t), Stabilization::default()).expect("valid body")
}

/// Plate lx x ly with its corner at the origin (x in [0, lx], y in [0, ly]).
pub fn corner_plate(
    lx: f64,
    ly: f64,
    nx: usize,
    ny: usize,
    kind: ElementKind,
    mat: Material,
    t: f64,
) -> Body {
    let mut m = plate(lx, ly, nx, ny, kind);
    m.transform(
        &nalgebra::Matrix3::identity(),
        Vec3::new(lx / 2.0, ly / 2.0, 0.0),
    );
    body(&m, mat, t)
}

/// Nodes whose coordinate `axis` is within tol of `value`.
pub fn nodes_at(b: &Body, axis: usize, value: f64, tol: f64) -> Vec<usize> {
    (0..b.state.x.len())
        .filter(|&i| (b.def.x0[i][axis] - value).abs() < tol)
        .collect()
}

pub fn kinds() -> [ElementKind; 2] {
    [ElementKind::Tri, ElementKind::Quad]
}

/// Observed order of convergence between successive (h, error) pairs.
pub fn orders(ladder: &[(f64, f64)]) -> Vec<f64> {
    ladder
        .windows(2)
        .map(|w| (w[0].1 / w[1].1).ln() / (w[0].0 / w[1].0).ln())
        .collect()
}

/// The stability study's free-vibration start on a plate of `lx` x `ly` centred at the
/// origin: a transverse velocity field inconsistent with the (zero) nodal rotations.
pub fn transverse_start(b: &mut Body, lx: f64, ly: f64) {
    for i in 0..b.state.x.len() {
        let p = b.def.x0[i];
        b.state.v[i] = Vec3::new(
            0.0,
            0.0,
            0.5 * (std::f64::consts::PI * p.x / lx).cos() * (p.y / ly),
        );
    }
}

/// Triangles on the left third, quads elsewhere; Kelvin and mass damping, one edge
/// clamped, the opposite edge driven by a ramped velocity program, spin in the start.
pub fn mixed_damped_plate() -> (Body, Vec3) {
    let (lx, ly, nx, ny) = (0.4, 0.25, 24, 15);
    let q = plate(lx, ly, nx, ny, ElementKind::Quad);
    let mut m = Mesh {
        nodes: q.nodes.clone(),
        ..Mesh::default()
    };
    for (e, c) in q.quads.iter().enumerate() {
        if e % nx < nx / 3 {
            m.tris.push([c[0], c[1], c[2]]);
            m.tris.push([c[0], c[2], c[3]]);
        } else {
            m.quads.push(*c);
        }
    }
    let mat = Material::new(7800.0, 200e9, 0.3, 1e-7).expect("valid");
    let mut b = Body::new(
        3,
        "mixed",
        &m,
        Section::new(mat, 0.002),
        Stabilization::default(),
    )
    .expect("valid");
    b.def_mut().mass_damping = 30.0;
    for i in 0..b.node_count() {
        let p = b.def.x0[i];
        b.state.v[i] = Vec3::new(0.3 * p.y, 0.0, 2.0 * (9.0 * p.x).sin() * (7.0 * p.y).cos());
        b.state.w[i] = Vec3::new(0.0, 5.0 * p.x, 0.0);
    }
    for n in nodes_at(&b, 0, -lx / 2.0, 1e-9) {
        b.fix(n, dof::ALL);
    }
    let driven = nodes_at(&b, 0, lx / 2.0, 1e-9);
    b.prescribe(
        &driven,
        VelocityProgram::ramped(Vec3::new(0.0, 0.0, 1.0), Vec3::zeros(), 1e-5),
    );
    (b, Vec3::new(0.0, 0.0, -9.81))
}
