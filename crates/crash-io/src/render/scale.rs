//! One colour scale per picture: the field, its unit and the range it maps to colours,
//! drawn as a vertical bar with the field name, unit, max and min written on it.

use super::colour::stress_colour;
use super::font::{draw_text, text_height, text_width};
use super::image::{Image, BLACK};
use super::scene::format_number;
use crate::frame::Frame;

/// A colour scale: values `min..max` (in SI units) map to blue..red.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    pub field: &'static str,
    /// Unit of the written numbers.
    pub unit: &'static str,
    /// SI value of one written unit (1e6 for MPa).
    pub unit_si: f64,
    /// Range in SI units.
    pub min: f64,
    pub max: f64,
}

impl Scale {
    /// von Mises stress (larger of top and bottom per element) over the bodies of
    /// `frame` that `shown` accepts; None when there is no finite value.
    pub fn von_mises(frame: &Frame, shown: impl Fn(u32) -> bool) -> Option<Scale> {
        let (lo, hi) = frame
            .bodies
            .iter()
            .filter(|b| shown(b.id))
            .flat_map(|b| (0..b.element_count()).map(move |e| b.von_mises_max(e)))
            .filter(|s| s.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        (lo <= hi).then_some(Scale {
            field: "von Mises",
            unit: "MPa",
            unit_si: 1e6,
            min: lo,
            max: hi,
        })
    }

    /// Position of `v` on the scale in [0, 1] (0.5 for a flat range).
    pub fn fraction(&self, v: f64) -> f64 {
        let span = self.max - self.min;
        if span > 0.0 && span.is_finite() {
            ((v - self.min) / span).clamp(0.0, 1.0)
        } else {
            0.5
        }
    }

    pub fn colour(&self, v: f64) -> [u8; 3] {
        stress_colour(self.fraction(v))
    }

    /// The text written on the picture: title ("von Mises [MPa]"), "max N", "min N".
    pub fn texts(&self) -> [String; 3] {
        [
            format!("{} [{}]", self.field, self.unit),
            format!("max {}", format_number(self.max / self.unit_si)),
            format!("min {}", format_number(self.min / self.unit_si)),
        ]
    }
}

/// Width of the legend strip for a picture of height `h` [px].
pub fn legend_width(h: u32) -> u32 {
    if h >= 400 {
        130
    } else {
        84
    }
}

/// Draw the scale in the strip right of `x0`: the title on top, a bar from min (bottom,
/// blue) to max (top, red), "max" above the bar and "min" below it, and three inner
/// ticks with values.
pub fn draw_scale(img: &mut Image, x0: i64, scale: &Scale) {
    let h = img.height as i64;
    let s = if h >= 400 { 2 } else { 1 };
    let th = text_height(s);
    let [title, max, min] = scale.texts();
    // The title wraps at " [" when the strip is narrow.
    let strip = img.width as i64 - x0;
    let mut y = 8;
    if text_width(&title, s) + 8 > strip {
        let (a, b) = title.split_at(title.find(" [").unwrap_or(title.len()));
        draw_text(img, x0 + 4, y, a, s, BLACK);
        y += th + 4;
        draw_text(img, x0 + 4, y, b.trim_start(), s, BLACK);
    } else {
        draw_text(img, x0 + 4, y, &title, s, BLACK);
    }
    y += th + 8;
    draw_text(img, x0 + 4, y, &max, s, BLACK);
    let top = y + th + 6;
    let bottom = h - 14 - th;
    if bottom - top < 20 {
        return;
    }
    draw_text(img, x0 + 4, bottom + 6, &min, s, BLACK);
    let (bx, bw) = (x0 + 8, 10 * s as i64);
    for yy in top..=bottom {
        let f = (bottom - yy) as f64 / (bottom - top) as f64;
        img.fill_rect(bx, yy, bw, 1, stress_colour(f));
    }
    img.stroke_rect(bx - 1, top - 1, bw + 2, bottom - top + 3, BLACK);
    for k in 1..=3 {
        let f = k as f64 / 4.0;
        let yy = bottom - ((bottom - top) as f64 * f).round() as i64;
        img.fill_rect(bx + bw, yy, 4, 1, BLACK);
        let v = scale.min + f * (scale.max - scale.min);
        let label = format_number(v / scale.unit_si);
        let tx = (bx + bw + 6).min(img.width as i64 - text_width(&label, s) - 2);
        draw_text(img, tx, yy - th / 2, &label, s, BLACK);
    }
}
