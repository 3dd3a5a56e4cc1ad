//! The energy history as a line plot: every term of the balance over time, with axes,
//! tick labels and a legend.

use super::font::{draw_text, text_height, text_width};
use super::image::{Image, Rgb, BLACK, WHITE};
use super::scene::format_number;
use crate::history::EnergyRow;

pub(crate) const GREY: Rgb = [225, 225, 225];

/// Ticks at 1, 2 or 5 times a power of ten covering [lo, hi] with about `n` steps.
pub fn nice_ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if hi <= lo || !lo.is_finite() || !hi.is_finite() {
        return vec![lo];
    }
    let raw = (hi - lo) / n.max(1) as f64;
    let p = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

struct Series {
    name: &'static str,
    colour: Rgb,
    value: fn(&EnergyRow) -> f64,
}

const SERIES: [Series; 7] = [
    Series {
        name: "kinetic",
        colour: [31, 119, 180],
        value: |r| r.energy.kinetic,
    },
    Series {
        name: "internal",
        colour: [255, 127, 14],
        value: |r| r.energy.internal,
    },
    Series {
        name: "hourglass",
        colour: [148, 103, 189],
        value: |r| r.energy.hourglass,
    },
    Series {
        name: "contact",
        colour: [214, 39, 40],
        value: |r| r.energy.contact,
    },
    Series {
        name: "damping",
        colour: [140, 86, 75],
        value: |r| r.energy.damping,
    },
    Series {
        name: "external work",
        colour: [44, 160, 44],
        value: |r| r.energy.external,
    },
    Series {
        name: "total - work",
        colour: [0, 0, 0],
        value: |r| r.energy.total(),
    },
];

/// Where the plot area sits in a picture: text scale, margins (room for y tick labels
/// on the left, the legend on the right, title and axis labels) and the area's size.
#[derive(Debug, Clone, Copy)]
pub struct PlotArea {
    pub s: u32,
    /// Width of the legend column.
    pub legend: i64,
    pub left: i64,
    pub right: i64,
    pub top: i64,
    pub bottom: i64,
    pub pw: i64,
    pub ph: i64,
}

impl PlotArea {
    /// `names` are the legend entries, `widest_tick` the widest y tick label expected.
    pub fn new<'a>(
        width: u32,
        height: u32,
        names: impl Iterator<Item = &'a str>,
        widest_tick: &str,
    ) -> Self {
        let s = if width >= 700 { 2 } else { 1 };
        let lw = names.map(|n| text_width(n, s)).max().unwrap_or(0) + 40;
        let (left, right, top, bottom) = (
            14 + text_width(widest_tick, s),
            lw + 24,
            18 + 2 * text_height(s),
            28 + 2 * text_height(s),
        );
        Self {
            s,
            legend: lw,
            left,
            right,
            top,
            bottom,
            pw: width as i64 - left - right,
            ph: height as i64 - top - bottom,
        }
    }

    /// Grid lines and tick labels of linear axes `x` and `y` (6 ticks each).
    pub fn grid(&self, img: &mut Image, x: (f64, f64), y: (f64, f64)) {
        let Self {
            s,
            left,
            top,
            pw,
            ph,
            ..
        } = *self;
        let ((t0, t1), (y0, y1)) = (x, y);
        let px = |v: f64| left as f64 + (v - t0) / (t1 - t0) * pw as f64;
        let py = |v: f64| (top + ph) as f64 - (v - y0) / (y1 - y0) * ph as f64;
        for v in nice_ticks(y0, y1, 6) {
            let y = py(v).round() as i64;
            img.fill_rect(left, y, pw, 1, GREY);
            let l = format_number(v);
            draw_text(
                img,
                left - 8 - text_width(&l, s),
                y - text_height(s) / 2,
                &l,
                s,
                BLACK,
            );
        }
        for v in nice_ticks(t0, t1, 6) {
            let x = px(v).round() as i64;
            img.fill_rect(x, top, 1, ph, GREY);
            img.fill_rect(x, top + ph, 1, 5, BLACK);
            let l = format_number(v);
            draw_text(img, x - text_width(&l, s) / 2, top + ph + 8, &l, s, BLACK);
        }
    }
}

/// Plot the energy terms of `rows` (time in ms on x, J on y).
pub fn energy_plot(rows: &[EnergyRow], width: u32, height: u32) -> Image {
    let mut img = Image::new(width, height, WHITE);
    // The legend sits right of the plot so it never hides a curve.
    let area = PlotArea::new(width, height, SERIES.iter().map(|se| se.name), "-8.88e-88");
    let PlotArea {
        s,
        legend: lw,
        left,
        top,
        pw,
        ph,
        ..
    } = area;
    let title = "Energy balance";
    draw_text(
        &mut img,
        (width as i64 - text_width(title, s)) / 2,
        8,
        title,
        s,
        BLACK,
    );
    if pw < 20 || ph < 20 {
        return img;
    }
    let finite = |v: f64| v.is_finite();
    let t: Vec<f64> = rows.iter().map(|r| r.time * 1e3).collect();
    let (t0, t1) = t
        .iter()
        .copied()
        .filter(|v| finite(*v))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let (mut y0, mut y1) = (0.0f64, 0.0f64);
    for r in rows {
        for se in &SERIES {
            let v = (se.value)(r);
            if finite(v) {
                y0 = y0.min(v);
                y1 = y1.max(v);
            }
        }
    }
    let (t0, t1) = if t1 > t0 {
        (t0, t1)
    } else if t0.is_finite() {
        (t0 - 1.0, t0 + 1.0)
    } else {
        (0.0, 1.0)
    };
    let pad = 0.05 * (y1 - y0).max(f64::MIN_POSITIVE);
    let (y0, y1) = if y1 > y0 {
        (y0 - if y0 < 0.0 { pad } else { 0.0 }, y1 + pad)
    } else {
        (-1.0, 1.0)
    };
    let px = |v: f64| left as f64 + (v - t0) / (t1 - t0) * pw as f64;
    let py = |v: f64| (top + ph) as f64 - (v - y0) / (y1 - y0) * ph as f64;

    area.grid(&mut img, (t0, t1), (y0, y1));
    img.stroke_rect(left, top, pw + 1, ph + 1, BLACK);
    let xl = "time [ms]";
    draw_text(
        &mut img,
        left + (pw - text_width(xl, s)) / 2,
        height as i64 - 6 - text_height(s),
        xl,
        s,
        BLACK,
    );
    draw_text(&mut img, 6, 8, "energy [J]", s, BLACK);

    // Lines, decimated to about two points per pixel column (min and max kept).
    for se in &SERIES {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .zip(&t)
            .map(|(r, &tt)| (px(tt), py((se.value)(r))))
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        let pts = decimate(&pts);
        for w in pts.windows(2) {
            img.line(w[0], w[1], 2.0, se.colour);
        }
        if pts.len() == 1 {
            img.line(pts[0], pts[0], 3.0, se.colour);
        }
    }

    let entries: Vec<(&str, Rgb)> = SERIES.iter().map(|se| (se.name, se.colour)).collect();
    draw_legend(&mut img, (left + pw + 14, top), lw, &entries, s);
    img
}

/// Legend box of width `lw` at `(lx, ly)`: a line sample and the name per entry.
pub(crate) fn draw_legend(
    img: &mut Image,
    (lx, ly): (i64, i64),
    lw: i64,
    entries: &[(&str, Rgb)],
    s: u32,
) {
    let lh = text_height(s) + 8;
    img.fill_rect(lx, ly, lw, lh * entries.len() as i64 + 8, WHITE);
    img.stroke_rect(lx, ly, lw, lh * entries.len() as i64 + 8, [160, 160, 160]);
    for (k, (name, colour)) in entries.iter().enumerate() {
        let y = ly + 6 + k as i64 * lh;
        let mid = (y + text_height(s) / 2) as f64;
        img.line(
            (lx as f64 + 6.0, mid),
            (lx as f64 + 28.0, mid),
            2.5,
            *colour,
        );
        draw_text(img, lx + 34, y, name, s, BLACK);
    }
}

/// Keep the first, min, max and last point of each pixel column, in order.
pub(crate) fn decimate(pts: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(pts.len().min(4096));
    let mut k = 0;
    while k < pts.len() {
        let col = pts[k].0.floor();
        let mut end = k;
        while end < pts.len() && pts[end].0.floor() == col {
            end += 1;
        }
        let run = &pts[k..end];
        if run.len() <= 4 {
            out.extend_from_slice(run);
        } else {
            let (mut lo, mut hi) = (0, 0);
            for (i, p) in run.iter().enumerate() {
                if p.1 < run[lo].1 {
                    lo = i;
                }
                if p.1 > run[hi].1 {
                    hi = i;
                }
            }
            let mut idx = [0, lo.min(hi), lo.max(hi), run.len() - 1];
            idx.sort_unstable();
            let mut last = usize::MAX;
            for i in idx {
                if i != last {
                    out.push(run[i]);
                    last = i;
                }
            }
        }
        k = end;
    }
    out
}
