//! Log–log line plots (e.g. a work–precision diagram: error against wall time), with
//! decade ticks, the energy plot's font, grid colour and legend.

use super::colour::body_colour;
use super::font::{draw_text, text_height, text_width};
use super::image::{Image, BLACK, WHITE};
use super::plot::{draw_legend, PlotArea, GREY};
use super::scene::format_number;

/// One named line of points (x, y); points that are not finite and > 0 are skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct LogSeries {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// Decade range [floor(log10 lo), ceil(log10 hi)] of the positive finite values, at
/// least one decade wide.
fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let (a, b) = (lo.log10().floor(), hi.log10().ceil());
    if b > a {
        (a, b)
    } else {
        (a, a + 1.0)
    }
}

/// Decade exponents to label: every one, or every k-th when there are many.
fn decade_ticks(a: f64, b: f64) -> Vec<f64> {
    let n = (b - a).round() as i64;
    let every = (n / 8 + 1).max(1);
    (0..=n)
        .filter(|k| k % every == 0)
        .map(|k| a + k as f64)
        .collect()
}

/// Plot `series` on logarithmic x and y axes, one colour per series, with markers.
pub fn loglog_plot(
    title: &str,
    (x_label, y_label): (&str, &str),
    series: &[LogSeries],
    width: u32,
    height: u32,
) -> Image {
    let mut img = Image::new(width, height, WHITE);
    let PlotArea {
        s,
        legend: lw,
        left,
        top,
        pw,
        ph,
        ..
    } = PlotArea::new(
        width,
        height,
        series.iter().map(|se| se.name.as_str()),
        "8.88e-88",
    );
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
    let all = || series.iter().flat_map(|se| se.points.iter());
    let (x0, x1) = decades(all().map(|p| p.0));
    let (y0, y1) = decades(all().map(|p| p.1));
    let px = |v: f64| left as f64 + (v.log10() - x0) / (x1 - x0) * pw as f64;
    let py = |v: f64| (top + ph) as f64 - (v.log10() - y0) / (y1 - y0) * ph as f64;
    for e in decade_ticks(y0, y1) {
        let y = py(10f64.powf(e)).round() as i64;
        img.fill_rect(left, y, pw, 1, GREY);
        let l = format_number(10f64.powf(e));
        let (tx, ty) = (left - 8 - text_width(&l, s), y - text_height(s) / 2);
        draw_text(&mut img, tx, ty, &l, s, BLACK);
    }
    for e in decade_ticks(x0, x1) {
        let x = px(10f64.powf(e)).round() as i64;
        img.fill_rect(x, top, 1, ph, GREY);
        img.fill_rect(x, top + ph, 1, 5, BLACK);
        let l = format_number(10f64.powf(e));
        draw_text(
            &mut img,
            x - text_width(&l, s) / 2,
            top + ph + 8,
            &l,
            s,
            BLACK,
        );
    }
    img.stroke_rect(left, top, pw + 1, ph + 1, BLACK);
    draw_text(
        &mut img,
        left + (pw - text_width(x_label, s)) / 2,
        height as i64 - 6 - text_height(s),
        x_label,
        s,
        BLACK,
    );
    draw_text(&mut img, 6, 8, y_label, s, BLACK);
    let mut entries = Vec::new();
    for (k, se) in series.iter().enumerate() {
        let colour = body_colour(k as u32);
        let pts: Vec<(f64, f64)> = se
            .points
            .iter()
            .filter(|p| p.0.is_finite() && p.0 > 0.0 && p.1.is_finite() && p.1 > 0.0)
            .map(|p| (px(p.0), py(p.1)))
            .collect();
        for w in pts.windows(2) {
            img.line(w[0], w[1], 2.0, colour);
        }
        let m = 3 * s as i64;
        for p in &pts {
            let (x, y) = (p.0.round() as i64, p.1.round() as i64);
            img.fill_rect(x - m, y - m, 2 * m + 1, 2 * m + 1, colour);
        }
        entries.push((se.name.as_str(), colour));
    }
    draw_legend(&mut img, (left + pw + 14, top), lw, &entries, s);
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decade_range_covers_the_values_and_is_at_least_one_decade() {
        assert_eq!(decades([0.003, 0.2].into_iter()), (-3.0, 0.0));
        assert_eq!(decades([1.0].into_iter()), (0.0, 1.0));
        assert_eq!(decades([f64::NAN, -1.0, 0.0].into_iter()), (0.0, 1.0));
    }

    #[test]
    fn points_and_the_line_between_them_sit_at_their_logarithmic_positions() {
        let se = LogSeries {
            name: "a".into(),
            points: vec![(0.1, 1e-3), (10.0, 1e-1)],
        };
        let img = loglog_plot("t", ("x", "y"), &[se], 800, 500);
        // frame: left 14 + width("8.88e-88") = 108, plot 618 x 398 px from top 46;
        // x spans 1e-1..1e1, y 1e-3..1e-1
        let c = body_colour(0);
        assert_eq!(img.get(108, 444), c);
        assert_eq!(img.get(726, 46), c);
        // (1, 1e-2) is the middle of both axes, on the (antialiased) straight line
        // between the points; away from it the plot is blank
        let d = |a: [u8; 3], b: [u8; 3]| (0..3).map(|k| a[k].abs_diff(b[k]) as u32).sum::<u32>();
        assert!(d(img.get(417, 245), c) < 100, "{:?}", img.get(417, 245));
        assert_eq!(img.get(300, 100), WHITE);
    }
}
