//! Isotropic linear elastic material with Kelvin viscoelastic damping (seed eq. 1–2).

use crate::error::CoreError;
use serde::{Deserialize, Serialize};

/// Hooke material: `sigma = C (eps + alpha * d eps/dt)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Mass density rho [kg/m^3].
    pub density: f64,
    /// Young's modulus E [Pa].
    pub young: f64,
    /// Poisson's ratio nu [-], in [0, 0.5).
    pub poisson: f64,
    /// Kelvin damping time alpha [s] (seed eq. 1); 0 means purely elastic.
    pub kelvin: f64,
}

impl Material {
    /// Structural steel: rho 7800 kg/m^3, E 200 GPa, nu 0.3, no damping (the material
    /// of the showcase scenes and of most tests).
    pub fn steel() -> Self {
        Self {
            density: 7800.0,
            young: 200e9,
            poisson: 0.3,
            kelvin: 0.0,
        }
    }

    pub fn new(density: f64, young: f64, poisson: f64, kelvin: f64) -> Result<Self, CoreError> {
        let m = Self {
            density,
            young,
            poisson,
            kelvin,
        };
        m.validate()?;
        Ok(m)
    }

    /// From the seed's Lamé pair: `Psi = lambda1 tr(eps)^2/2 + lambda2 eps:eps`.
    pub fn from_lame(
        density: f64,
        lambda1: f64,
        lambda2: f64,
        kelvin: f64,
    ) -> Result<Self, CoreError> {
        if !(lambda2.is_finite() && lambda2 > 0.0) {
            return Err(CoreError::Material {
                field: "lambda2",
                value: lambda2,
                valid: "the shear modulus lambda2 must be finite and > 0",
            });
        }
        if !(lambda1.is_finite() && lambda1 >= 0.0) {
            return Err(CoreError::Material {
                field: "lambda1",
                value: lambda1,
                valid: "lambda1 must be finite and >= 0 (Poisson's ratio in [0, 0.5))",
            });
        }
        let young = lambda2 * (3.0 * lambda1 + 2.0 * lambda2) / (lambda1 + lambda2);
        let poisson = lambda1 / (2.0 * (lambda1 + lambda2));
        Self::new(density, young, poisson, kelvin)
    }

    pub fn validate(&self) -> Result<(), CoreError> {
        if !(self.density.is_finite() && self.density > 0.0) {
            return Err(CoreError::Material {
                field: "density",
                value: self.density,
                valid: "must be finite and > 0 (kg/m^3)",
            });
        }
        if !(self.young.is_finite() && self.young > 0.0) {
            return Err(CoreError::Material {
                field: "young",
                value: self.young,
                valid: "must be finite and > 0 (Pa)",
            });
        }
        if !(self.poisson.is_finite() && (0.0..0.5).contains(&self.poisson)) {
            return Err(CoreError::Material {
                field: "poisson",
                value: self.poisson,
                valid: "must be in [0, 0.5)",
            });
        }
        if !(self.kelvin.is_finite() && self.kelvin >= 0.0) {
            return Err(CoreError::Material {
                field: "kelvin",
                value: self.kelvin,
                valid: "must be finite and >= 0 (s)",
            });
        }
        Ok(())
    }

    /// Plane-stress modulus E / (1 - nu^2).
    pub fn plate_modulus(&self) -> f64 {
        self.young / (1.0 - self.poisson * self.poisson)
    }

    pub fn shear_modulus(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }

    /// Plate membrane wave speed c = sqrt(E / (rho (1 - nu^2))).
    pub fn wave_speed(&self) -> f64 {
        (self.plate_modulus() / self.density).sqrt()
    }
}

/// A shell section: material and thickness, with the closed-form resultant stiffnesses
/// (an elastic shell needs no through-thickness integration points).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Section {
    pub material: Material,
    pub thickness: f64,
    /// Membrane stiffness t * E / (1 - nu^2).
    pub membrane: f64,
    /// Bending stiffness D = E t^3 / (12 (1 - nu^2)).
    pub bending: f64,
    /// Transverse shear stiffness kappa G t, kappa = 5/6.
    pub shear: f64,
    /// Wave speed c.
    pub wave_speed: f64,
}

/// Reissner–Mindlin shear correction factor.
pub const SHEAR_CORRECTION: f64 = 5.0 / 6.0;

impl Section {
    pub fn new(material: Material, thickness: f64) -> Self {
        let ep = material.plate_modulus();
        Self {
            material,
            thickness,
            membrane: ep * thickness,
            bending: ep * thickness.powi(3) / 12.0,
            shear: SHEAR_CORRECTION * material.shear_modulus() * thickness,
            wave_speed: material.wave_speed(),
        }
    }

    /// Apply a plane-stress matrix scaled by `k` (k = t E/(1-nu^2) for membrane,
    /// D for bending) to an engineering strain (xx, yy, 2xy).
    #[inline(always)]
    pub fn plane(&self, k: f64, e: [f64; 3]) -> [f64; 3] {
        let nu = self.material.poisson;
        [
            k * (e[0] + nu * e[1]),
            k * (nu * e[0] + e[1]),
            k * 0.5 * (1.0 - nu) * e[2],
        ]
    }

    /// Complementary energy density `s . C^-1 s / 2` for a plane-stress resultant
    /// with stiffness scale `k`.
    #[inline(always)]
    pub fn plane_energy(&self, k: f64, s: [f64; 3]) -> f64 {
        let nu = self.material.poisson;
        (s[0] * s[0] + s[1] * s[1] - 2.0 * nu * s[0] * s[1] + 2.0 * (1.0 + nu) * s[2] * s[2])
            / (2.0 * k * (1.0 - nu * nu))
    }

    /// Damping correction of the critical time step for Kelvin damping:
    /// xi = alpha c / L_e, factor sqrt(1 + xi^2) - xi.
    #[inline(always)]
    pub fn damping_factor(&self, length: f64) -> f64 {
        let a = self.material.kelvin;
        if a == 0.0 {
            return 1.0;
        }
        let xi = a * self.wave_speed / length;
        (1.0 + xi * xi).sqrt() - xi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lame_pair_round_trips_to_young_and_poisson() {
        let m = Material::steel();
        let mu = m.shear_modulus();
        let lambda = m.young * m.poisson / ((1.0 + m.poisson) * (1.0 - 2.0 * m.poisson));
        let back = Material::from_lame(7800.0, lambda, mu, 0.0).expect("valid");
        assert!((back.young - m.young).abs() < 1e-3);
        assert!((back.poisson - m.poisson).abs() < 1e-12);
    }

    #[test]
    fn steel_membrane_wave_speed_is_5308() {
        let m = Material::steel();
        assert!((m.wave_speed() - 5308.0).abs() < 1.0, "{}", m.wave_speed());
    }

    #[test]
    fn plane_energy_is_half_stress_times_strain() {
        let s = Section::new(Material::new(1000.0, 1e9, 0.25, 0.0).expect("v"), 0.01);
        let e = [1e-3, -2e-4, 5e-4];
        let n = s.plane(s.membrane, e);
        let w = 0.5 * (n[0] * e[0] + n[1] * e[1] + n[2] * e[2]);
        assert!((s.plane_energy(s.membrane, n) - w).abs() < 1e-12 * w.abs());
    }

    #[test]
    fn poisson_half_is_rejected() {
        assert!(Material::new(1000.0, 1e9, 0.5, 0.0).is_err());
    }
}
