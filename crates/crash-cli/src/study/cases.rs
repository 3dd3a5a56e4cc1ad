//! The verification suite: every case with its ladders, tolerance and expected order.

use super::ladder::{CaseError, Level, Measurement};
use super::{contact, structural};
use crash_core::shapes::ElementKind;

const BOTH: &[ElementKind] = &[ElementKind::Tri, ElementKind::Quad];
const TRI: &[ElementKind] = &[ElementKind::Tri];

/// One verification case.
#[derive(Debug)]
pub struct Case {
    /// Short name (file names, `--only`).
    pub id: &'static str,
    pub title: &'static str,
    /// What is measured, with its unit.
    pub quantity: &'static str,
    /// Where the reference comes from.
    pub reference: &'static str,
    /// What the mesh parameter of a level means.
    pub mesh_param: &'static str,
    pub kinds: &'static [ElementKind],
    /// Mesh ladders of `crash study --quick` and of the full study.
    pub quick: &'static [u32],
    pub full: &'static [u32],
    /// Time-step ladder (safety factors) at the finest quick mesh, full study only.
    pub dt_ladder: &'static [f64],
    /// Largest error allowed at the finest level of either ladder.
    pub tolerance: f64,
    /// Smallest observed order allowed between the two finest levels (quick ladder).
    pub min_order: Option<f64>,
    pub run: fn(ElementKind, Level) -> Result<Measurement, CaseError>,
}

pub static CASES: &[Case] = &[
    Case {
        id: "fv52",
        title: "NAFEMS FV52: simply supported thick plate, first frequency",
        quantity: "f1 [Hz]",
        reference: "NAFEMS FV52: 45.897 Hz (L = 10 m, t = 1 m, E = 200 GPa, nu = 0.3, rho = 8000 kg/m^3)",
        mesh_param: "cells per side",
        kinds: BOTH,
        quick: &[4, 8, 16],
        full: &[4, 8, 16, 32, 64],
        dt_ladder: &[0.9, 0.45, 0.225],
        tolerance: 0.02,
        min_order: Some(1.5),
        run: structural::fv52,
    },
    Case {
        id: "thin-plate",
        title: "Thin simply supported plate, first frequency against Kirchhoff",
        quantity: "f11 [Hz]",
        reference: "Kirchhoff f11 = (pi/2)(2/a^2) sqrt(D/(rho t)), a = 1 m, t = 10 mm steel: 48.11 Hz",
        mesh_param: "cells per side",
        kinds: BOTH,
        quick: &[4, 8, 16],
        full: &[4, 8, 16, 32, 64],
        dt_ladder: &[],
        tolerance: 0.02,
        min_order: Some(1.5),
        run: structural::thin_plate,
    },
    Case {
        id: "cantilever",
        title: "Thin cantilever strip, tip deflection under an end load",
        quantity: "tip deflection [m]",
        reference: "beam theory P L^3 / (3 E I), L = 1 m, b = 0.1 m, t = 10 mm, nu = 0, P = 1 N",
        mesh_param: "cells along the strip (1 across per 10 along)",
        kinds: BOTH,
        quick: &[10, 20, 40],
        full: &[10, 20, 40, 80],
        dt_ladder: &[],
        tolerance: 0.02,
        min_order: Some(1.5),
        run: structural::cantilever,
    },
    Case {
        id: "wave-speed",
        title: "Membrane wave speed along a laterally constrained strip",
        quantity: "c [m/s]",
        reference: "c = sqrt(E / (rho (1 - nu^2))) = 5308.2 m/s (steel: E = 200 GPa, nu = 0.3, rho = 7800 kg/m^3)",
        mesh_param: "cells along the 1 m strip",
        kinds: BOTH,
        quick: &[50, 100, 200],
        full: &[50, 100, 200, 400, 800],
        dt_ladder: &[],
        tolerance: 0.02,
        min_order: None,
        run: structural::wave_speed,
    },
    Case {
        id: "rigid-rotation",
        title: "Rigid-body rotation of a free tilted plate (one turn): spurious strain energy",
        quantity: "max (E_int + E_hg) / E_kin",
        reference: "0 (the physical centrifugal part is ~2e-10)",
        mesh_param: "cells per side",
        kinds: BOTH,
        quick: &[2],
        full: &[2, 4, 8],
        dt_ladder: &[],
        tolerance: 1e-9,
        min_order: None,
        run: structural::rigid_rotation,
    },
    Case {
        id: "reissner",
        title: "Reissner point-load stiffness of a spherical shell, loaded through contact",
        quantity: "k [N/m]",
        reference: "k = 4 E t^2 / (R sqrt(3(1-nu^2))), R = 0.1 m, t = 1 mm (chord slope for w <= t/2)",
        mesh_param: "icosphere level of the cap",
        kinds: TRI,
        quick: &[4, 5],
        full: &[4, 5, 6],
        dt_ladder: &[],
        tolerance: 0.10,
        min_order: None,
        run: |_, l| contact::reissner(l),
    },
    Case {
        id: "bounce",
        title: "Sphere bouncing on a rigid plate in the linear range: contact duration",
        quantity: "contact duration [s]",
        reference: "pi sqrt(m / k) with Reissner's k (R = 0.1 m, t = 1 mm, 0.5 m/s)",
        mesh_param: "icosphere level",
        kinds: TRI,
        quick: &[3, 4],
        full: &[3, 4, 5],
        dt_ladder: &[0.9, 0.45],
        tolerance: 0.15,
        min_order: None,
        run: |_, l| contact::bounce(l),
    },
    Case {
        id: "spheres-head-on",
        title: "Two equal spheres head-on: exchange of velocities, conservation of momentum",
        quantity: "-v_after / v_before",
        reference: "1 (elastic exchange); momentum conserved to round-off",
        mesh_param: "icosphere level",
        kinds: TRI,
        quick: &[2, 3],
        full: &[2, 3, 4, 5],
        dt_ladder: &[],
        tolerance: 0.05,
        min_order: None,
        run: |_, l| contact::spheres_head_on(l),
    },
    Case {
        id: "sphere-on-plate",
        title: "Sphere dropped on a fixed plate: energy balance",
        quantity: "max energy-balance error",
        reference: "0 (E_kin + E_int + E_hg + E_c + E_d - W = E_0)",
        mesh_param: "icosphere level",
        kinds: TRI,
        quick: &[3],
        full: &[3, 4, 5],
        dt_ladder: &[],
        tolerance: 0.02,
        min_order: None,
        run: |_, l| contact::sphere_on_plate(l),
    },
];
