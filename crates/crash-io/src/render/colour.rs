//! Colours: a distinct palette for bodies, the turbo map for stress, Lambert shading.

use super::image::Rgb;

/// Tableau-10: distinct, print-friendly body colours.
const PALETTE: [Rgb; 10] = [
    [78, 121, 167],
    [242, 142, 43],
    [225, 87, 89],
    [118, 183, 178],
    [89, 161, 79],
    [237, 201, 72],
    [176, 122, 161],
    [255, 157, 167],
    [156, 117, 95],
    [186, 176, 172],
];

pub fn body_colour(id: u32) -> Rgb {
    PALETTE[id as usize % PALETTE.len()]
}

/// Turbo colour map (Google, polynomial fit) at s in [0, 1]: blue - green - red.
pub fn turbo(s: f64) -> Rgb {
    let x = if s.is_finite() {
        s.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let poly = |c: [f64; 6]| c[0] + x * (c[1] + x * (c[2] + x * (c[3] + x * (c[4] + x * c[5]))));
    let r = poly([
        0.13572138,
        4.61539260,
        -42.66032258,
        132.13108234,
        -152.94239396,
        59.28637943,
    ]);
    let g = poly([
        0.09140261,
        2.19418839,
        4.84296658,
        -14.18503333,
        4.27729857,
        2.82956604,
    ]);
    let b = poly([
        0.10667330,
        12.64194608,
        -60.58204836,
        110.36276771,
        -89.90310912,
        27.34824973,
    ]);
    [r, g, b].map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// Stress colour for s in [0, 1]: turbo without its darkest ends, so low stress reads
/// as blue and high stress as red on shaded surfaces.
pub fn stress_colour(s: f64) -> Rgb {
    let x = if s.is_finite() {
        s.clamp(0.0, 1.0)
    } else {
        1.0
    };
    turbo(0.1 + 0.82 * x)
}

/// Scale a colour by a light intensity in [0, 1].
pub fn shade(c: Rgb, k: f64) -> Rgb {
    c.map(|v| (v as f64 * k).round().clamp(0.0, 255.0) as u8)
}
