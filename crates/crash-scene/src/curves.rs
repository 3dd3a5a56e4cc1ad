//! Load curves (`[curves.NAME] points = [[t, v], ...]`): checked, evaluated, and
//! recognised when they are a ramp the solver core runs as such.
//!
//! A curve is linear between its points, holds its first value before the first point
//! and its last value after the last one. `Curve::as_ramp` finds the curves that are a
//! core ramp (a prescribed velocity constant after a linear ramp from t = 0, a nodal
//! load constant after a linear ramp from t0 to t1): those run as ramps, bit for bit as
//! before curves existed; the others run as `crash_core::TimeCurve` tables.

use crate::context::Ctx;
use crate::error::SceneError;
use crate::schema::SceneFile;
use std::collections::BTreeMap;

/// Relative tolerance when comparing curve values (fraction of the largest |value|).
pub const CURVE_TOL: f64 = 1e-12;

/// A checked curve: at least one point, finite, times strictly increasing.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    pub points: Vec<(f64, f64)>,
}

/// `value * ramp_factor(t, t0, t1)` for t >= 0: 0 before t0, linear to `value` at t1,
/// then constant (t1 == t0: a step at t0; t0 == t1 == 0: constant from the start).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramp {
    pub t0: f64,
    pub t1: f64,
    pub value: f64,
}

impl Curve {
    /// The curve's value at time t.
    pub fn value(&self, t: f64) -> f64 {
        let p = &self.points;
        let i = p.partition_point(|q| q.0 <= t);
        if i == 0 {
            return p[0].1;
        }
        if i == p.len() {
            return p[p.len() - 1].1;
        }
        let (a, b) = (p[i - 1], p[i]);
        a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
    }

    /// The curve as a ramp, when it is one for t >= 0 (see `Ramp`).
    pub fn as_ramp(&self) -> Option<Ramp> {
        let scale = self
            .points
            .iter()
            .map(|p| p.1.abs())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let same = |a: f64, b: f64| (a - b).abs() <= CURVE_TOL * scale;
        // the breakpoints of the curve on [0, inf)
        let mut p: Vec<(f64, f64)> = vec![(0.0, self.value(0.0))];
        p.extend(self.points.iter().copied().filter(|q| q.0 > 0.0));
        // a constant tail adds nothing
        while p.len() >= 2 && same(p[p.len() - 1].1, p[p.len() - 2].1) {
            p.pop();
        }
        // interior points on the line through their neighbours add nothing
        let mut i = 1;
        while i + 1 < p.len() {
            let (a, b, c) = (p[i - 1], p[i], p[i + 1]);
            let on_line = a.1 + (c.1 - a.1) * (b.0 - a.0) / (c.0 - a.0);
            if same(b.1, on_line) {
                p.remove(i);
            } else {
                i += 1;
            }
        }
        match p.as_slice() {
            [(_, v)] => Some(Ramp {
                t0: 0.0,
                t1: 0.0,
                value: *v,
            }),
            [(_, a), (t1, v)] if same(*a, 0.0) => Some(Ramp {
                t0: 0.0,
                t1: *t1,
                value: *v,
            }),
            [(_, a), (t0, b), (t1, v)] if same(*a, 0.0) && same(*b, 0.0) => Some(Ramp {
                t0: *t0,
                t1: *t1,
                value: *v,
            }),
            _ => None,
        }
    }

    /// A short description for messages: `3 points, 0 at 0 s ... 5 at 0.002 s`.
    pub fn describe(&self) -> String {
        let (first, last) = (self.points[0], self.points[self.points.len() - 1]);
        format!(
            "{} point(s), {} at {} s ... {} at {} s",
            self.points.len(),
            first.1,
            first.0,
            last.1,
            last.0
        )
    }
}

/// Every curve of the scene, checked, by name.
pub fn curves(ctx: &Ctx, s: &SceneFile) -> Result<BTreeMap<String, Curve>, SceneError> {
    let mut out = BTreeMap::new();
    for (name, c) in &s.curves {
        let key = format!("curves.{name}.points");
        if c.points.is_empty() {
            return Err(ctx.invalid(&key, "a curve needs at least one point [time, value]"));
        }
        for (k, p) in c.points.iter().enumerate() {
            let pk = format!("{key}[{k}]");
            if !(p[0].is_finite() && p[1].is_finite()) {
                return Err(ctx.invalid(&pk, "time and value must be finite"));
            }
            if k > 0 && p[0] <= c.points[k - 1][0] {
                return Err(ctx.invalid(
                    &pk,
                    format!(
                        "time {} is not after the previous point's {}: times must increase",
                        p[0],
                        c.points[k - 1][0]
                    ),
                ));
            }
        }
        out.insert(
            name.clone(),
            Curve {
                points: c.points.iter().map(|p| (p[0], p[1])).collect(),
            },
        );
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(p: &[(f64, f64)]) -> Curve {
        Curve { points: p.to_vec() }
    }

    #[test]
    fn values_are_linear_between_points_and_constant_outside() {
        let k = c(&[(1.0, 2.0), (3.0, 6.0)]);
        assert_eq!(k.value(0.0), 2.0);
        assert_eq!(k.value(2.0), 4.0);
        assert_eq!(k.value(3.0), 6.0);
        assert_eq!(k.value(9.0), 6.0);
    }

    #[test]
    fn ramps_then_constants_are_recognised() {
        let r = |t0, t1, value| Some(Ramp { t0, t1, value });
        assert_eq!(c(&[(0.0, 5.0)]).as_ramp(), r(0.0, 0.0, 5.0));
        assert_eq!(c(&[(0.0, 5.0), (1.0, 5.0)]).as_ramp(), r(0.0, 0.0, 5.0));
        assert_eq!(c(&[(0.0, 0.0), (2.0, 5.0)]).as_ramp(), r(0.0, 2.0, 5.0));
        assert_eq!(
            c(&[(0.0, 0.0), (1.0, 2.5), (2.0, 5.0), (9.0, 5.0)]).as_ramp(),
            r(0.0, 2.0, 5.0)
        );
        assert_eq!(
            c(&[(0.0, 0.0), (1.0, 0.0), (2.0, -3.0), (4.0, -3.0)]).as_ramp(),
            r(1.0, 2.0, -3.0)
        );
        // points before t = 0 do not matter
        assert_eq!(
            c(&[(-1.0, 7.0), (0.0, 0.0), (1.0, 1.0)]).as_ramp(),
            r(0.0, 1.0, 1.0)
        );
        assert_eq!(c(&[(0.0, 0.0)]).as_ramp(), r(0.0, 0.0, 0.0));
    }

    #[test]
    fn other_shapes_are_not_ramps() {
        // rises and falls back
        assert_eq!(c(&[(0.0, 0.0), (1.0, 1.0), (2.0, 0.0)]).as_ramp(), None);
        // starts at a non-zero value, then changes
        assert_eq!(c(&[(0.0, 1.0), (1.0, 2.0)]).as_ramp(), None);
        // two slopes
        assert_eq!(c(&[(0.0, 0.0), (1.0, 1.0), (2.0, 3.0)]).as_ramp(), None);
    }
}
