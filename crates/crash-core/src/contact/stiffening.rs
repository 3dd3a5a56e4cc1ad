//! The penalty law of the segment pass (`quadrature.rs`): a point pressed x = delta / c
//! into the contact surface (delta = -g, c the contact distance) stores
//! k c^2 psi(x) and is pushed by k c phi(x), phi = psi', with
//!
//! ```text
//! phi(x) = x / (1 - x)^2 + x^3 / X1^2
//! ```
//!
//! (k the point's linear stiffness). At small depth phi = x: the linear penalty. The
//! cubic term stiffens it from about X1 c on, where a curved body's contact patch is
//! still small (a per-area penalty on a curved surface is a Hertz contact, soft at small
//! depth), and the barrier term grows without bound as the point approaches the other
//! body's mid-surface (x -> 1). Beyond `CAP` the force goes on linearly with the slope
//! at `CAP` (finite everywhere, still one potential). One potential per point, so the
//! forces stay its exact gradient and the work of contact is given back.
//! docs/theory-contact.md, "Segment pass", "Depth".

use super::config::SOFT_SCALE_LIMIT;

/// Depth (share of c) from which the cubic term matters: at X1 c it equals the linear
/// term (with the barrier term the force is then 2.6 times the linear penalty's).
pub const X1: f64 = 0.2;
/// Depth (share of c) beyond which the force is continued linearly.
pub const CAP: f64 = 0.95;

fn phi_raw(x: f64) -> f64 {
    let r = 1.0 - x;
    x / (r * r) + x * x * x / (X1 * X1)
}

fn tangent_raw(x: f64) -> f64 {
    let r = 1.0 - x;
    (1.0 + x) / (r * r * r) + 3.0 * x * x / (X1 * X1)
}

fn psi_raw(x: f64) -> f64 {
    // 1/(1-x) - 1 + ln(1-x), written to keep its x^2/2 leading term at small x
    x / (1.0 - x) + (-x).ln_1p() + x.powi(4) / (4.0 * X1 * X1)
}

/// phi(x): the force of a point pressed x = delta / c deep, per k c (x >= 0).
pub fn force(x: f64) -> f64 {
    if x <= CAP {
        phi_raw(x)
    } else {
        phi_raw(CAP) + tangent_raw(CAP) * (x - CAP)
    }
}

/// phi'(x): the point's tangent stiffness per k (increasing in x).
pub fn tangent(x: f64) -> f64 {
    tangent_raw(x.min(CAP))
}

/// psi(x): the energy a point pressed x deep stores, per k c^2.
pub fn potential(x: f64) -> f64 {
    if x <= CAP {
        psi_raw(x)
    } else {
        let d = x - CAP;
        psi_raw(CAP) + phi_raw(CAP) * d + 0.5 * tangent_raw(CAP) * d * d
    }
}

/// The step of a pair whose deepest point is x deep under penalty scale `scale`, when
/// the law stiffens it past the soft rule's limit: a point's tangent stiffness is
/// `scale` phi'(x) times s_0 m / dt_ref^2 of the soft rule, stable while that factor
/// times (h / dt_ref)^2 stays within `SOFT_SCALE_LIMIT` (config.rs). `pair_dt`: the
/// pair's step before contact (elements, closing speed), dt_ref = 0.9 of it; the driver
/// takes 0.9 of the returned step, so h / dt_ref stays at most sqrt(limit / factor).
pub fn step(scale: f64, x: f64, pair_dt: f64) -> Option<f64> {
    let s_eff = scale * tangent(x);
    (s_eff > SOFT_SCALE_LIMIT).then(|| pair_dt * (SOFT_SCALE_LIMIT / s_eff).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// phi is the derivative of psi and phi' of phi (central differences), on both sides
    /// of the cap; phi = x to first order.
    #[test]
    fn force_is_the_derivative_of_the_potential() {
        for i in 1..200 {
            let x = i as f64 * 0.006;
            let h = 1e-6;
            let dpsi = (potential(x + h) - potential(x - h)) / (2.0 * h);
            let dphi = (force(x + h) - force(x - h)) / (2.0 * h);
            assert!((dpsi - force(x)).abs() < 1e-6 * force(x).max(1.0), "{x}");
            assert!((dphi - tangent(x)).abs() < 1e-5 * tangent(x), "{x}");
        }
        let x = 1e-4;
        assert!((force(x) / x - 1.0).abs() < 3e-4);
        assert!((potential(x) / (0.5 * x * x) - 1.0).abs() < 1e-3);
    }
}
