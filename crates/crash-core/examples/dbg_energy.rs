use crash_core::shapes::{plate, ElementKind};
use crash_core::*;
fn main() {
    let g = |k: &str, d: f64| std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(d);
    let kind = if std::env::args().nth(1).as_deref() == Some("quad") { ElementKind::Quad } else { ElementKind::Tri };
    let mut m = plate(0.2, 0.1, 8, 4, kind);
    for (i, p) in m.nodes.iter_mut().enumerate() {
        let s = ((i * 7919) % 13) as f64 / 13.0 - 0.5;
        if p.x.abs() < 0.099 && p.y.abs() < 0.049 { p.x += g("DIST", 0.15) * s * 0.2 / 8.0; p.y -= 0.1 * s * 0.1 / 4.0; }
    }
    let mut s = Stabilization::default(); s.drilling = g("DR", s.drilling);
    let mut b = Body::new(0, "b", &m, Section::new(Material::new(7800.0, 200e9, 0.3, 0.0).unwrap(), 0.002), s).unwrap();
    let amp = g("AMP", 0.5);
    for i in 0..b.x.len() { let p = b.x0[i]; b.v[i] = Vec3::new(0.0, 0.0, amp * (std::f64::consts::PI * p.x / 0.2).cos() * (p.y / 0.1)); }
    let mut run = Run::new(Group::new(vec![b], Vec3::zeros()), RunConfig { end_time: f64::INFINITY, safety: g("SAF", 0.9), ..Default::default() }).unwrap();
    for k in 0..100000 { run.step().unwrap(); if k % 10000 == 0 { let e = run.energy; println!("{k} ke={:.4e} ie={:.4e} err={:.3e}", e.kinetic, e.internal, e.balance_error); } }
}
