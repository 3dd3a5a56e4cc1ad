//! Derived element quantities for output: stress resultants and surface stresses.

use crate::body::{Body, BodyDef};
use crate::element::membrane::{gradient, green};
use crate::Vec3;

/// Stress resultants of one element: membrane forces per length (Nxx, Nyy, Nxy) from
/// the second Piola–Kirchhoff stress (small strain: ~Cauchy) and bending moments per
/// length (Mxx, Myy, Mxy), both in the element's co-rotational frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Resultants {
    pub n: [f64; 3],
    pub m: [f64; 3],
}

impl Resultants {
    /// von Mises stress at the top (z = +t/2) and bottom (z = -t/2) surfaces:
    /// sigma = N/t -/+ 6 M / t^2 (sign: M positive compresses the top fibre).
    pub fn von_mises(&self, t: f64) -> (f64, f64) {
        let vm = |s: [f64; 3]| (s[0] * s[0] - s[0] * s[1] + s[1] * s[1] + 3.0 * s[2] * s[2]).sqrt();
        let f =
            |sign: f64| std::array::from_fn(|c| self.n[c] / t + sign * 6.0 * self.m[c] / (t * t));
        (vm(f(1.0)), vm(f(-1.0)))
    }
}

impl Body {
    /// Resultants of every element (triangles first, then quads).
    pub fn resultants(&self) -> Vec<Resultants> {
        let mut out = Vec::with_capacity(self.element_count());
        self.resultants_each(|r| out.push(r));
        out
    }

    /// Each element's resultants in that order, without a vector (a frame's capture
    /// writes them straight into its arrays).
    pub fn resultants_each(&self, f: impl FnMut(Resultants)) {
        let shell = &self.state.shell;
        resultants_of(&self.def, &self.state.x, |k| shell[k].m, f);
    }
}

/// The resultants of every element of `def` at positions `x` (triangles first, then
/// quads), each element's bending moments `m(k)` taken as they are: the membrane forces
/// follow from the positions, so a frame can derive them away from the step loop.
pub fn resultants_of(
    def: &BodyDef,
    x: &[Vec3],
    m: impl Fn(usize) -> [f64; 3],
    mut f: impl FnMut(Resultants),
) {
    let sec = &def.section;
    for (k, e) in def.tris.iter().enumerate() {
        let p = e.nodes.map(|n| x[n as usize]);
        let (f1, f2) = gradient(&p, &e.bx0, &e.by0);
        f(Resultants {
            n: sec.plane(sec.membrane, green(&f1, &f2)),
            m: m(k),
        });
    }
    let nt = def.tris.len();
    for (k, e) in def.quads.iter().enumerate() {
        let p = e.nodes.map(|n| x[n as usize]);
        let (f1, f2) = gradient(&p, &e.bx0_all(), &e.by0_all());
        let g = green(&f1, &f2);
        f(Resultants {
            n: sec.plane(
                sec.membrane,
                [g[0] - e.e0[0], g[1] - e.e0[1], g[2] - e.e0[2]],
            ),
            m: m(nt + k),
        });
    }
}
