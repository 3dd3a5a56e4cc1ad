//! Runs whole steps (integrate, guards, element forces, energies, boxes) of a plate
//! group repeatedly, for instruction counting with `valgrind --tool=callgrind`
//! (repeatable on a busy machine): `step_loop [tri|quad] [steps]`.

use crash_core::shapes::{plate, ElementKind};
use crash_core::{Body, Clock, Group, Material, Section, Stabilization, Vec3};

fn main() {
    let mut args = std::env::args().skip(1);
    let kind = match args.next().as_deref() {
        Some("quad") => ElementKind::Quad,
        _ => ElementKind::Tri,
    };
    let steps: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(20);
    let n = if kind == ElementKind::Tri { 71 } else { 100 };
    let m = plate(1.0, 1.0, n, n, kind);
    let sec = Section::new(Material::steel(), 0.002);
    let mut b = Body::new(0, "plate", &m, sec, Stabilization::default()).expect("valid body");
    for i in 0..b.state.x.len() {
        let p = b.def.x0[i];
        b.state.v[i] = Vec3::new(0.0, 0.0, 0.1 * (7.0 * p.x).sin() * (5.0 * p.y).cos());
    }
    let elements = b.element_count();
    let mut g = Group::new(vec![b], Vec3::zeros());
    g.start().expect("start");
    let mut clock = Clock::default();
    let start = std::time::Instant::now();
    for _ in 0..steps {
        g.advance(&clock, 1e-7).expect("step");
        clock = clock.after(1e-7);
    }
    let ns = start.elapsed().as_nanos() as f64 / (steps * elements) as f64;
    println!("{elements} elements x {steps} steps, {ns:.1} ns per element-cycle");
}
