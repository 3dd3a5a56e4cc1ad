//! Section cut: the shells of a frame cut by a plane, drawn as lines in the plane (one
//! colour per body), so the contact zone shows even where a body hides it in 3D.

use super::camera::{Projector, View};
use super::colour::body_colour;
use super::font::{draw_label, draw_text, text_height, text_width};
use super::image::{Image, BLACK, WHITE};
use super::scene::{format_number, format_time};
use crate::frame::Frame;
use crash_core::Vec3;

/// A plane: the points p with (p - point) . normal = 0 (normal of unit length).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    pub point: Vec3,
    pub normal: Vec3,
}

/// One straight piece of a shell's cut line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutSegment {
    pub body: u32,
    pub a: Vec3,
    pub b: Vec3,
}

impl Plane {
    pub fn distance(&self, p: &Vec3) -> f64 {
        (p - self.point).dot(&self.normal)
    }

    /// The cut of a flat or warped polygon: its edges' crossings, paired in order (two
    /// for a plane polygon; four for a warped quad cut across its saddle). A vertex on
    /// the plane counts on the positive side, so no crossing is counted twice; a cut that
    /// only touches a vertex (zero length) is no segment.
    pub fn cut_polygon(&self, pts: &[Vec3]) -> Vec<(Vec3, Vec3)> {
        let d: Vec<f64> = pts.iter().map(|p| self.distance(p)).collect();
        let mut cross = Vec::with_capacity(4);
        for i in 0..pts.len() {
            let j = (i + 1) % pts.len();
            if (d[i] >= 0.0) != (d[j] >= 0.0) {
                let t = d[i] / (d[i] - d[j]);
                cross.push(pts[i] + t * (pts[j] - pts[i]));
            }
        }
        cross
            .chunks_exact(2)
            .map(|c| (c[0], c[1]))
            .filter(|(a, b)| a != b)
            .collect()
    }
}

/// Cut every element of `frame` (bodies other than `hidden`) by `plane`.
pub fn cut_frame(frame: &Frame, plane: &Plane, hidden: Option<u32>) -> Vec<CutSegment> {
    let mut out = Vec::new();
    for b in frame.bodies.iter().filter(|b| Some(b.id) != hidden) {
        let tris = b.tris.iter().map(|t| t.as_slice());
        let quads = b.quads.iter().map(|q| q.as_slice());
        for nodes in tris.chain(quads) {
            let pts: Vec<Vec3> = nodes.iter().map(|&n| b.x[n as usize]).collect();
            for (a, c) in plane.cut_polygon(&pts) {
                out.push(CutSegment {
                    body: b.id,
                    a,
                    b: c,
                });
            }
        }
    }
    out
}

/// What a section picture shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    pub plane: Plane,
    /// In-plane direction drawn upward (the contact normal).
    pub up: Vec3,
    /// Centre of the picture [m], on the plane.
    pub centre: Vec3,
    /// The point marked with a cross (the contact zone's centre) [m].
    pub mark: Vec3,
    /// Half of the visible width [m].
    pub half_width: f64,
}

impl Section {
    /// The camera: looking at the plane along its normal, `up` upward.
    pub fn view(&self, width: u32, height: u32) -> View {
        View {
            target: self.centre,
            direction: self.plane.normal,
            up: self.up,
            half_width: self.half_width,
            half_height: self.half_width * height as f64 / width.max(1) as f64,
        }
    }
}

/// Scale bar length: 1, 2 or 5 x 10^k, about a fifth of `span`.
fn bar_length(span: f64) -> f64 {
    let raw = span / 5.0;
    let p = 10f64.powf(raw.log10().floor());
    [5.0, 2.0, 1.0]
        .iter()
        .map(|m| m * p)
        .find(|l| *l <= raw)
        .unwrap_or(p)
}

/// A component for "{:.2}" without "-0.00".
fn tidy(v: f64) -> f64 {
    if v.abs() < 0.005 {
        0.0
    } else {
        v
    }
}

/// Length with a readable unit: "20 mm", "1.5 m".
fn format_length(l: f64) -> String {
    if l >= 1.0 {
        format!("{} m", format_number(l))
    } else if l >= 1e-3 {
        format!("{} mm", format_number(l * 1e3))
    } else {
        format!("{} um", format_number(l * 1e6))
    }
}

/// Draw the cut of `frame` by `section` in a `width` x `height` picture: the time and
/// `caption` on top, the plane's point and normal at the bottom, a scale bar and the
/// body names in their colours. Returns the picture and the segments drawn.
pub fn render_section(
    frame: &Frame,
    section: &Section,
    width: u32,
    height: u32,
    caption: Option<&str>,
) -> (Image, Vec<CutSegment>) {
    let mut img = Image::new(width, height, WHITE);
    let view = section.view(width, height);
    let proj = Projector::new(&view, (0.0, 0.0, width as f64, height as f64));
    let segments = cut_frame(frame, &section.plane, None);
    let lw = if width >= 600 { 2.5 } else { 1.8 };
    for s in &segments {
        let (p, q) = (proj.project(&s.a), proj.project(&s.b));
        img.line((p.0, p.1), (q.0, q.1), lw, body_colour(s.body));
    }
    // The centre of the zone: a small grey cross.
    let c = proj.project(&section.mark);
    let grey = [150, 150, 150];
    img.line((c.0 - 6.0, c.1), (c.0 + 6.0, c.1), 1.0, grey);
    img.line((c.0, c.1 - 6.0), (c.0, c.1 + 6.0), 1.0, grey);

    let s = if width >= 600 { 2 } else { 1 };
    let th = text_height(s);
    draw_label(
        &mut img,
        8,
        8,
        &format!("t = {}", format_time(frame.time)),
        s,
        BLACK,
    );
    let mut y = 14 + th;
    if let Some(c) = caption {
        draw_label(&mut img, 8, y, c, s, BLACK);
        y += th + 6;
    }
    // Body names, in their colours, under the labels.
    let mut drawn: Vec<u32> = segments.iter().map(|s| s.body).collect();
    drawn.sort_unstable();
    drawn.dedup();
    for id in drawn {
        if let Some(b) = frame.bodies.iter().find(|b| b.id == id) {
            let name = if b.name.is_empty() {
                format!("- body {id}")
            } else {
                format!("- {}", b.name)
            };
            draw_label(&mut img, 8, y, &name, s, body_colour(id));
            y += th + 6;
        }
    }
    // Scale bar, bottom right.
    let l = bar_length(2.0 * section.half_width);
    let px = l * width as f64 / (2.0 * section.half_width);
    let (x1, yb) = (width as f64 - 12.0, height as f64 - 14.0 - th as f64);
    img.line((x1 - px, yb), (x1, yb), 2.0, BLACK);
    let label = format_length(l);
    let lx = x1 as i64 - text_width(&label, s);
    draw_text(&mut img, lx, yb as i64 - th - 6, &label, s, BLACK);
    // Where the plane is.
    let (p, n) = (section.plane.point, section.plane.normal);
    let plane = format!(
        "cut through ({}, {}, {}) mm, normal ({:.2}, {:.2}, {:.2})",
        format_number(p.x * 1e3),
        format_number(p.y * 1e3),
        format_number(p.z * 1e3),
        tidy(n.x),
        tidy(n.y),
        tidy(n.z)
    );
    let ps = if text_width(&plane, s) + 16 > lx {
        1
    } else {
        s
    };
    draw_label(
        &mut img,
        8,
        height as i64 - 8 - text_height(ps),
        &plane,
        ps,
        BLACK,
    );
    (img, segments)
}
