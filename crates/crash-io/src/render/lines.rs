//! A general line plot (time on x): axes fitted to the data, ticks, a legend right of
//! the plot, vertical markers for the key moments and a note line under the title.

use super::font::{draw_text, text_height, text_width};
use super::image::{Image, Rgb, BLACK, WHITE};
use super::plot::{decimate, draw_legend, PlotArea};

/// One named line.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    pub name: String,
    pub colour: Rgb,
    /// (x, y) in the plot's units; non-finite points are skipped.
    pub points: Vec<(f64, f64)>,
}

/// A vertical marker at `x` with a short label.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    pub x: f64,
    pub label: String,
}

/// What to draw around the lines.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Labels<'a> {
    pub title: &'a str,
    pub x: &'a str,
    pub y: &'a str,
    /// A line under the title (e.g. where the data came from).
    pub note: Option<&'a str>,
}

/// The ranges the axes show.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Axes {
    pub x: (f64, f64),
    pub y: (f64, f64),
}

/// Axes that hold every finite point: x from the smallest to the largest x; y from
/// min(0, smallest y) to the largest y plus 5 % (minus 5 % below a negative minimum).
pub fn fit_axes(lines: &[Line]) -> Axes {
    let pts = lines
        .iter()
        .flat_map(|l| l.points.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, 0.0f64);
    for &(x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let x = if x1 > x0 {
        (x0, x1)
    } else if x0.is_finite() {
        (x0 - 1.0, x0 + 1.0)
    } else {
        (0.0, 1.0)
    };
    let pad = 0.05 * (y1 - y0);
    let y = if y1 > y0 {
        (y0 - if y0 < 0.0 { pad } else { 0.0 }, y1 + pad)
    } else {
        (-1.0, 1.0)
    };
    Axes { x, y }
}

/// Plot `lines` in a `width` x `height` picture; returns it and the axes' ranges.
pub fn line_plot(
    lines: &[Line],
    markers: &[Marker],
    labels: &Labels,
    width: u32,
    height: u32,
) -> (Image, Axes) {
    let mut img = Image::new(width, height, WHITE);
    let names = lines.iter().map(|l| l.name.as_str());
    let area = PlotArea::new(width, height, names, "-8.88e-88");
    let PlotArea {
        s,
        legend: lw,
        left,
        pw,
        ..
    } = area;
    let th = text_height(s);
    let top = area.top + if labels.note.is_some() { th + 6 } else { 0 };
    let ph = area.ph - (top - area.top);
    let axes = fit_axes(lines);
    let centred = |img: &mut Image, y: i64, t: &str| {
        draw_text(img, (width as i64 - text_width(t, s)) / 2, y, t, s, BLACK);
    };
    centred(&mut img, 8, labels.title);
    if let Some(n) = labels.note {
        centred(&mut img, 14 + th, n);
    }
    if pw < 20 || ph < 20 {
        return (img, axes);
    }
    let ((t0, t1), (y0, y1)) = (axes.x, axes.y);
    let px = |v: f64| left as f64 + (v - t0) / (t1 - t0) * pw as f64;
    let py = |v: f64| (top + ph) as f64 - (v - y0) / (y1 - y0) * ph as f64;
    PlotArea { top, ph, ..area }.grid(&mut img, (t0, t1), (y0, y1));
    // Markers: dashed grey verticals, labels stacked from the top so they do not overlap.
    for (k, m) in markers.iter().enumerate() {
        if !(m.x >= t0 && m.x <= t1) {
            continue;
        }
        let x = px(m.x).round() as i64;
        for y in (top..top + ph).step_by(8) {
            img.fill_rect(x, y, 1, 4, [110, 110, 110]);
        }
        let ly = top + 4 + (k as i64 % 4) * (th + 4);
        let lx = (x + 4).min(left + pw - text_width(&m.label, s) - 2);
        draw_text(&mut img, lx, ly, &m.label, s, [80, 80, 80]);
    }
    img.stroke_rect(left, top, pw + 1, ph + 1, BLACK);
    let xl = labels.x;
    let bottom_y = height as i64 - 6 - th;
    draw_text(
        &mut img,
        left + (pw - text_width(xl, s)) / 2,
        bottom_y,
        xl,
        s,
        BLACK,
    );
    draw_text(&mut img, 6, 8, labels.y, s, BLACK);
    for l in lines {
        let pts: Vec<(f64, f64)> = l
            .points
            .iter()
            .map(|&(x, y)| (px(x), py(y)))
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        let pts = decimate(&pts);
        for w in pts.windows(2) {
            img.line(w[0], w[1], 2.0, l.colour);
        }
        if pts.len() == 1 {
            img.line(pts[0], pts[0], 3.0, l.colour);
        }
    }
    let entries: Vec<(&str, Rgb)> = lines.iter().map(|l| (l.name.as_str(), l.colour)).collect();
    if !entries.is_empty() {
        draw_legend(&mut img, (left + pw + 14, top), lw, &entries, s);
    }
    (img, axes)
}
