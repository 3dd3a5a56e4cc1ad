//! Bodies interpenetrating at t = 0, found by the core's contact search
//! (`crash_core::contact::initial_penetrations`).
//!
//! Thickness-inflated bounding boxes overlapping is not an error by itself (a sphere
//! resting on a plate overlaps its box): for candidate pairs every node of one body is
//! measured against the other's segments, and a node nearer than the sum of the half
//! thicknesses is a penetration. A node deep inside a closed body, farther than that
//! from every face, is not detected.

use crash_core::contact::{initial_penetrations, ContactConfig};
use crash_core::Body;

pub use crash_core::contact::Penetration;

/// The deepest initial penetration between two different contact bodies, if any
/// (None when contact is off).
pub fn check_initial_overlap(bodies: &[Body], cfg: &ContactConfig) -> Option<Penetration> {
    if !cfg.enabled {
        return None;
    }
    initial_penetrations(bodies, cfg)
        .into_iter()
        .fold(None, |worst: Option<Penetration>, p| match worst {
            Some(w) if w.depth >= p.depth => Some(w),
            _ => Some(p),
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crash_core::Vec3;

    fn plate_at(id: u32, z: f64, t: f64) -> Body {
        use crash_core::shapes::{plate, ElementKind};
        use crash_core::{Material, Section, Stabilization};
        let mut m = plate(1.0, 1.0, 4, 4, ElementKind::Quad);
        m.transform(&nalgebra::Matrix3::identity(), Vec3::new(0.0, 0.0, z));
        let mat = Material::steel();
        let mut b =
            Body::new(id, "p", &m, Section::new(mat, t), Stabilization::default()).expect("valid");
        b.def_mut().contact = true;
        b
    }

    #[test]
    fn parallel_plates_closer_than_their_half_thicknesses_interpenetrate() {
        let cfg = ContactConfig {
            margin: 0.01,
            ..ContactConfig::default()
        };
        // half thicknesses 0.01 + 0.02 = 0.03 m, mid-planes 0.025 m apart: 5 mm deep
        let close = [plate_at(0, 0.0, 0.02), plate_at(1, 0.025, 0.04)];
        let p = check_initial_overlap(&close, &cfg).expect("penetration");
        assert!((p.depth - 0.005).abs() < 1e-12, "{p:?}");
        // every one of the 25 nodes of the node body is inside
        assert_eq!(p.nodes, 25);
        let apart = [plate_at(0, 0.0, 0.02), plate_at(1, 0.031, 0.04)];
        assert_eq!(check_initial_overlap(&apart, &cfg), None);
        let off = ContactConfig {
            enabled: false,
            ..cfg
        };
        assert_eq!(check_initial_overlap(&close, &off), None);
        let mut no_contact = close.clone();
        no_contact[1].def_mut().contact = false;
        assert_eq!(check_initial_overlap(&no_contact, &cfg), None);
    }
}
