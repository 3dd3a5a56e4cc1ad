//! Load curves: piecewise-linear time tables that scale prescribed velocities and
//! nodal loads. Linear between points; before the first point the first value, after
//! the last point the last value (constant extrapolation, as LS-DYNA's *DEFINE_CURVE
//! is commonly used for loads held after the last point).

use serde::{Deserialize, Serialize};

/// No curve: the program or load uses its ramp.
pub const NO_CURVE: u32 = u32::MAX;

/// A time table (t_i, v_i) with strictly increasing, finite times (at least one point).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TimeCurve {
    pub points: Vec<(f64, f64)>,
}

impl TimeCurve {
    /// The curve's value at t.
    pub fn value(&self, t: f64) -> f64 {
        let p = &self.points;
        let i = p.partition_point(|q| q.0 <= t);
        if i == 0 {
            return p.first().map_or(0.0, |q| q.1);
        }
        if i == p.len() {
            return p[p.len() - 1].1;
        }
        let (a, b) = (p[i - 1], p[i]);
        a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
    }

    /// The slope of the piece that starts at or before t and ends after it (0 before
    /// the first point and from the last point on, where the value is held).
    pub fn slope(&self, t: f64) -> f64 {
        let p = &self.points;
        let i = p.partition_point(|q| q.0 <= t);
        if i == 0 || i == p.len() {
            return 0.0;
        }
        let (a, b) = (p[i - 1], p[i]);
        (b.1 - a.1) / (b.0 - a.0)
    }

    /// Whether the table is usable: a point at least, finite, times increasing.
    pub fn is_valid(&self) -> bool {
        !self.points.is_empty()
            && self
                .points
                .iter()
                .all(|p| p.0.is_finite() && p.1.is_finite())
            && self.points.windows(2).all(|w| w[1].0 > w[0].0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_between_points_constant_outside() {
        let c = TimeCurve {
            points: vec![(1.0, 2.0), (3.0, 6.0), (4.0, 0.0)],
        };
        assert_eq!(c.value(0.0), 2.0);
        assert_eq!(c.value(2.0), 4.0);
        assert_eq!(c.value(3.5), 3.0);
        assert_eq!(c.value(9.0), 0.0);
    }
}
