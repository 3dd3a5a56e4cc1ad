//! Body builders shared by the verification cases (steel shells, SI units). They follow
//! the setups of crash-core's physics tests (crates/crash-core/tests/).

use crash_core::shapes::{icosphere, plate, ElementKind};
use crash_core::{dof, Body, CoreError, Material, Mesh, Section, Stabilization, Vec3};

pub fn steel() -> Material {
    Material {
        density: 7800.0,
        young: 200e9,
        poisson: 0.3,
        kelvin: 0.0,
    }
}

/// Steel with another Poisson ratio (checked by `Material::new`).
pub fn steel_nu(nu: f64) -> Result<Material, CoreError> {
    Material::new(7800.0, 200e9, nu, 0.0)
}

pub fn body(id: u32, mesh: &Mesh, mat: Material, t: f64) -> Result<Body, CoreError> {
    Body::new(
        id,
        &format!("b{id}"),
        mesh,
        Section::new(mat, t),
        Stabilization::default(),
    )
}

pub fn translate(m: &mut Mesh, by: Vec3) {
    for p in &mut m.nodes {
        *p += by;
    }
}

/// Plate lx x ly with its corner at the origin (x in [0, lx], y in [0, ly]).
pub fn corner_plate(
    lx: f64,
    ly: f64,
    (nx, ny): (usize, usize),
    kind: ElementKind,
    mat: Material,
    t: f64,
) -> Result<Body, CoreError> {
    let mut m = plate(lx, ly, nx, ny, kind);
    translate(&mut m, Vec3::new(lx / 2.0, ly / 2.0, 0.0));
    body(0, &m, mat, t)
}

/// Nodes whose initial coordinate `axis` is within tol of `value`.
pub fn nodes_at(b: &Body, axis: usize, value: f64, tol: f64) -> Vec<usize> {
    (0..b.state.x.len())
        .filter(|&i| (b.def.x0[i][axis] - value).abs() < tol)
        .collect()
}

/// The node nearest to `p` (initial position).
pub fn nearest(b: &Body, p: Vec3) -> usize {
    (0..b.def.x0.len())
        .min_by(|&i, &j| {
            (b.def.x0[i] - p)
                .norm()
                .total_cmp(&(b.def.x0[j] - p).norm())
        })
        .unwrap_or(0)
}

/// Contact shell of material `mat`.
pub fn shell(id: u32, mesh: &Mesh, mat: Material, t: f64) -> Result<Body, CoreError> {
    let mut b = body(id, mesh, mat, t)?;
    b.def_mut().contact = true;
    Ok(b)
}

/// Icosphere shell of radius r at `centre`, moving rigidly with `v`.
pub fn sphere(
    id: u32,
    (r, t): (f64, f64),
    level: u32,
    mat: Material,
    centre: Vec3,
    v: Vec3,
) -> Result<Body, CoreError> {
    let mut m = icosphere(r, level);
    translate(&mut m, centre);
    let mut b = shell(id, &m, mat, t)?;
    b.set_rigid_velocity(v, Vec3::zeros(), centre);
    Ok(b)
}

/// Square plate lx x lx in the plane z = z0, n x n quads, every DOF held.
pub fn fixed_plate(id: u32, lx: f64, n: usize, t: f64, z0: f64) -> Result<Body, CoreError> {
    let mut m = plate(lx, lx, n, n, ElementKind::Quad);
    translate(&mut m, Vec3::new(0.0, 0.0, z0));
    let mut b = shell(id, &m, steel(), t)?;
    for i in 0..b.state.x.len() {
        b.fix(i, dof::ALL);
    }
    Ok(b)
}

pub use crash_core::shapes::spherical_cap as cap;

/// Reissner's point-load stiffness of a thin spherical shell: 4 E t^2 / (R sqrt(3(1-nu^2))).
pub fn reissner_stiffness(m: &Material, r: f64, t: f64) -> f64 {
    4.0 * m.young * t * t / (r * (3.0 * (1.0 - m.poisson * m.poisson)).sqrt())
}

/// Mean edge of an icosphere of radius r at `level` (docs/scene-format.md).
pub fn sphere_edge(r: f64, level: u32) -> f64 {
    r * 1.0515 / f64::from(1u32 << level)
}

/// Velocity of the centre of mass.
pub fn com_velocity(b: &Body) -> Vec3 {
    b.linear_momentum() / b.total_mass()
}
