//! Element sizes, a critical time step estimate and the default contact margin.
//!
//! Rule for the default margin (docs/scene-format.md, "contact"):
//! `margin = MARGIN_ELEMENT_FRACTION * h_min + 2 * v_max * dt_est * MARGIN_STEPS`
//! where `h_min` is the smallest characteristic element length among contact bodies,
//! `v_max` the largest node speed any body can reach (initial and prescribed speeds,
//! plus |g| * end_time), the factor 2 for two bodies closing on each other, and
//! `dt_est = safety * min(L_e / c)` the time step estimate.

use crash_core::{Body, Vec3};

/// Fraction of the smallest element length kept as the search margin.
pub const MARGIN_ELEMENT_FRACTION: f64 = 0.25;
/// Steps the margin must cover at the largest closing speed (the master's box update
/// interval may not exceed this).
pub const MARGIN_STEPS: f64 = 10.0;

/// Characteristic length of each element, triangles then quads: the smallest altitude
/// 2A / (longest edge) of a triangle, A / (longest diagonal) of a quad (the lengths the
/// explicit time step is set by).
pub fn element_lengths(
    x: &[Vec3],
    tris: impl Iterator<Item = [u32; 3]>,
    quads: impl Iterator<Item = [u32; 4]>,
) -> Vec<f64> {
    let mut out = Vec::new();
    for t in tris {
        let p = t.map(|n| x[n as usize]);
        let area2 = (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
        let longest = (p[1] - p[0])
            .norm()
            .max((p[2] - p[1]).norm())
            .max((p[0] - p[2]).norm());
        out.push(area2 / longest);
    }
    for q in quads {
        let p = q.map(|n| x[n as usize]);
        let area = 0.5 * (p[2] - p[0]).cross(&(p[3] - p[1])).norm();
        let diag = (p[2] - p[0]).norm().max((p[3] - p[1]).norm());
        out.push(area / diag);
    }
    out
}

/// Smallest characteristic element length of a body.
pub fn min_length(b: &Body) -> f64 {
    element_lengths(
        &b.state.x,
        b.def.tris.iter().map(|e| e.nodes),
        b.def.quads.iter().map(|e| e.nodes),
    )
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

/// Critical time step estimate L_min / c (no safety factor; Kelvin damping lowers it
/// by sqrt(1 + xi^2) - xi). The core's own element loop gives the exact value.
pub fn dt_estimate(b: &Body) -> f64 {
    let l = min_length(b);
    crash_core::forces::element_dt(&b.def.section, l)
}

/// Largest node speed at t = 0, including rigid rotation and prescribed programs.
pub fn max_speed(b: &Body) -> f64 {
    let v0 = b.state.v.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let vp = b
        .def
        .programs
        .iter()
        .map(|p| p.velocity.norm())
        .fold(0.0, f64::max);
    v0.max(vp)
}

/// What the default margin needs of one body (so that a planner need not keep it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarginInputs {
    pub contact: bool,
    pub min_length: f64,
    pub dt_estimate: f64,
    pub max_speed: f64,
}

impl MarginInputs {
    pub fn of(b: &Body) -> Self {
        Self {
            contact: b.def.contact,
            min_length: min_length(b),
            dt_estimate: dt_estimate(b),
            max_speed: max_speed(b),
        }
    }
}

/// The default contact margin of a set of bodies (see the module docs).
pub fn default_margin(bodies: &[Body], gravity: Vec3, end_time: f64, safety: f64) -> f64 {
    let inputs: Vec<MarginInputs> = bodies.iter().map(MarginInputs::of).collect();
    default_margin_of(&inputs, gravity, end_time, safety)
}

/// The default contact margin from each body's inputs.
pub fn default_margin_of(
    bodies: &[MarginInputs],
    gravity: Vec3,
    end_time: f64,
    safety: f64,
) -> f64 {
    let contact: Vec<&MarginInputs> = bodies.iter().filter(|b| b.contact).collect();
    if contact.is_empty() {
        return 0.0;
    }
    let h = contact
        .iter()
        .map(|b| b.min_length)
        .fold(f64::INFINITY, f64::min);
    let dt = safety
        * bodies
            .iter()
            .map(|b| b.dt_estimate)
            .fold(f64::INFINITY, f64::min);
    let v = contact.iter().map(|b| b.max_speed).fold(0.0, f64::max) + gravity.norm() * end_time;
    MARGIN_ELEMENT_FRACTION * h + 2.0 * v * dt * MARGIN_STEPS
}
