use crash_core::body::dof;
use crash_core::shapes::{plate, ElementKind};
use crash_core::*;
fn main() {
    let kind = if std::env::args().nth(1).as_deref() == Some("tri") { ElementKind::Tri } else { ElementKind::Quad };
    let (l, b, t) = (1.0, 0.1, 0.01);
    let mat = Material::new(7800.0, 200e9, 0.0, 0.0).unwrap();
    let mut m = plate(l, b, 40, 2, kind);
    m.transform(&nalgebra::Matrix3::identity(), Vec3::new(l / 2.0, b / 2.0, 0.0));
    let mut body = Body::new(0, "b", &m, Section::new(mat, t), { let mut s = Stabilization::default(); let g = |k: &str, d: f64| std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(d); s.drilling = g("DR", s.drilling); s.hourglass_w = g("HW", s.hourglass_w); s.hourglass_rotation = g("HR", s.hourglass_rotation); s.hourglass_membrane = g("HM", s.hourglass_membrane); s }).unwrap();
    let e = 200e9; let inertia = b * t * t * t / 12.0;
    let moment = 2.0 * std::f64::consts::PI * e * inertia / l;
    let omega1 = 1.875f64.powi(2) * (e * inertia / (7800.0 * b * t)).sqrt() / (l * l);
    body.mass_damping = 2.0 * omega1;
    let mut tip = vec![];
    for i in 0..body.x.len() { if body.x0[i].x.abs() < 1e-9 { body.fix(i, dof::ALL); } if (body.x0[i].x - l).abs() < 1e-9 { tip.push(i); } }
    let n = tip.len() - 1;
    tip.sort_by(|&i, &j| body.x0[i].y.total_cmp(&body.x0[j].y));
    for (k, &node) in tip.iter().enumerate() {
        let w = if k == 0 || k == n { 0.5 } else { 1.0 } / n as f64;
        body.add_load(NodalLoad { node: node as u32, force: Vec3::zeros(), moment: Vec3::new(0.0, -moment * w, 0.0), t0: 0.0, t1: 0.6 });
    }
    let mut run = Run::new(Group::new(vec![body], Vec3::zeros()), RunConfig { end_time: 1.0, runaway_limit: 10.0, ..Default::default() }).unwrap();
    let mut k = 0;
    let r = run.run(|r| { k += 1; if k % 20000 == 0 { let e = r.energy; let b = &r.group.bodies[0]; let hg = b.hourglass[79]; let st = b.shell[79]; println!("hg79 w={:.3e} th={:.3e},{:.3e} m={:.3e},{:.3e},{:.3e} q={:.3e},{:.3e} d={:.3e}", hg.w, hg.th[0], hg.th[1], st.m[0], st.m[1], st.m[2], st.q[0], st.q[1], st.drill); println!("t={:.3} ke={:.3e} ie={:.4e} hg={:.3e} d={:.4e} w={:.4e} err={:.4}", r.time(), e.kinetic, e.internal, e.hourglass, e.damping, e.external, e.balance_error); } });
    println!("{r:?}");
}
