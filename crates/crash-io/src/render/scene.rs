//! Pictures of a frame: shaded shells coloured by body or by von Mises stress, with the
//! time and (for stress) the picture's one colour scale.

use super::camera::{Projector, View};
use super::colour::{body_colour, shade};
use super::font::{draw_label, text_height, text_width};
use super::image::{Image, Rgb, BLACK, WHITE};
use super::raster::Raster;
use super::scale::{draw_scale, legend_width, Scale};
use crate::frame::Frame;
use crash_core::Vec3;

/// What the surface colour shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Colouring {
    /// One colour per body (by id).
    ByBody,
    /// Larger of top/bottom von Mises stress per element over `range` [Pa]
    /// (None: the range of the bodies shown in this picture).
    ByVonMises { range: Option<(f64, f64)> },
}

/// Where the camera looks from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Camera {
    /// 3/4 view fitted to this frame. For a series, fit once with `View::fit_frames`
    /// and pass `Camera::View` so every picture shares it.
    Auto,
    View(View),
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions<'a> {
    pub width: u32,
    pub height: u32,
    pub colour: Colouring,
    pub camera: Camera,
    /// Print "t = ..." in the top-left corner.
    pub time_label: bool,
    /// Outline elements that are large enough on screen.
    pub edges: bool,
    /// A body left out of the picture (e.g. the plate in a view from below).
    pub hidden: Option<u32>,
    /// A second line under the time label (why this frame was chosen).
    pub caption: Option<&'a str>,
}

impl Default for RenderOptions<'_> {
    fn default() -> Self {
        Self {
            width: 800,
            height: 600,
            colour: Colouring::ByBody,
            camera: Camera::Auto,
            time_label: true,
            edges: true,
            hidden: None,
            caption: None,
        }
    }
}

/// Supersampling factor of the 3D part (anti-aliasing).
const SUPERSAMPLE: u32 = 2;
/// Element outlines are drawn for bodies whose elements average at least this many
/// (final) pixels on screen.
const EDGE_MIN_PX: f64 = 9.0;
/// Height of the band above the picture kept free for the time label [px].
const LABEL_BAND: u32 = 30;

/// The colour scale `render_frame` draws on the picture of `frame` (None when coloured
/// by body, or when no shown element has a finite stress).
pub fn frame_scale(frame: &Frame, opts: &RenderOptions) -> Option<Scale> {
    match opts.colour {
        Colouring::ByBody => None,
        Colouring::ByVonMises { range } => {
            let own = Scale::von_mises(frame, |id| Some(id) != opts.hidden);
            match range {
                Some((lo, hi)) if hi >= lo => own.map(|s| Scale {
                    min: lo,
                    max: hi,
                    ..s
                }),
                _ => own,
            }
        }
    }
}

/// Time with a readable unit: "1.250 ms".
pub fn format_time(t: f64) -> String {
    let a = t.abs();
    if a == 0.0 {
        "0 s".into()
    } else if a >= 1.0 {
        format!("{t:.4} s")
    } else if a >= 1e-3 {
        format!("{:.3} ms", t * 1e3)
    } else {
        format!("{:.3} us", t * 1e6)
    }
}

/// Short number for labels: 3 significant digits, exponent form when far from 1.
pub fn format_number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.2e}");
        s.replace(".00e", "e").replace("0e", "e")
    } else {
        let digits = (2 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    }
}

fn light_intensity(n: &Vec3, light: &Vec3) -> f64 {
    // Two-sided: shells are seen from both faces.
    0.32 + 0.68 * n.dot(light).abs()
}

/// Mean on-screen length of the first edge of each element [px].
fn mean_edge_px(pts: &[(f64, f64, f64)], b: &crate::frame::FrameBody) -> f64 {
    let len = |a: u32, c: u32| {
        let (p, q) = (pts[a as usize], pts[c as usize]);
        ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt()
    };
    let sum: f64 = b.tris.iter().map(|t| len(t[0], t[1])).sum::<f64>()
        + b.quads.iter().map(|q| len(q[0], q[1])).sum::<f64>();
    sum / b.element_count().max(1) as f64
}

/// Render one frame.
pub fn render_frame(frame: &Frame, opts: &RenderOptions) -> Image {
    let scale = frame_scale(frame, opts);
    let plot_w = if scale.is_some() {
        opts.width.saturating_sub(legend_width(opts.height))
    } else {
        opts.width
    };
    let ss = SUPERSAMPLE;
    let view = match opts.camera {
        Camera::View(v) => Some(v),
        Camera::Auto => View::fit_frames(std::iter::once(frame)),
    };
    let mut raster = Raster::new(Image::new(plot_w * ss, opts.height * ss, WHITE));
    if let Some(view) = view {
        // Keep the top band free for the time label (and caption).
        let lines = if opts.caption.is_some() { 2 } else { 1 };
        let band = if opts.time_label {
            (lines * LABEL_BAND).min(opts.height / 4)
        } else {
            0
        };
        let viewport = (
            0.0,
            (band * ss) as f64,
            (plot_w * ss) as f64,
            ((opts.height - band) * ss) as f64,
        );
        let proj = Projector::new(&view, viewport);
        let (r, u, f) = proj.axes();
        let light = (-0.35 * r + 0.55 * u - 0.75 * f).normalize();
        let edge_w = 0.6 * ss as f64;
        for b in frame.bodies.iter().filter(|b| Some(b.id) != opts.hidden) {
            let pts: Vec<_> = b.x.iter().map(|p| proj.project(p)).collect();
            // Outline the elements of a body only if they are large on screen on average:
            // deciding per body keeps a mesh uniformly outlined or not at all.
            let outline = opts.edges && mean_edge_px(&pts, b) > EDGE_MIN_PX * ss as f64;
            let base = body_colour(b.id);
            let colour_of = |e: usize| -> Rgb {
                match &scale {
                    None => base,
                    Some(sc) => sc.colour(b.von_mises_max(e)),
                }
            };
            let mut draw = |nodes: [u32; 3], c: Rgb, mask: u8| {
                let q = nodes.map(|n| b.x[n as usize]);
                let nrm = (q[1] - q[0]).cross(&(q[2] - q[0]));
                let k = if nrm.norm() > 0.0 {
                    light_intensity(&nrm.normalize(), &light)
                } else {
                    1.0
                };
                let c = shade(c, k);
                let edge = (shade(c, 0.72), edge_w);
                let mask = if outline { mask } else { 0 };
                raster.triangle(nodes.map(|n| pts[n as usize]), c, mask, edge);
            };
            for (e, t) in b.tris.iter().enumerate() {
                draw(*t, colour_of(e), 0b111);
            }
            let nt = b.tris.len();
            for (e, q) in b.quads.iter().enumerate() {
                let c = colour_of(nt + e);
                draw([q[0], q[1], q[2]], c, 0b101);
                draw([q[0], q[2], q[3]], c, 0b011);
            }
        }
    }
    let mut img = Image::new(opts.width, opts.height, WHITE);
    img.paste(&raster.image.downsample(ss), 0, 0);
    if opts.time_label {
        let s = if opts.width >= 300 { 2 } else { 1 };
        let text = if opts.width >= 600 {
            format!("t = {}   step {}", format_time(frame.time), frame.step)
        } else {
            format!("t = {}", format_time(frame.time))
        };
        draw_label(&mut img, 8, 8, &text, s, BLACK);
        if let Some(c) = opts.caption {
            // Smaller text when the caption would run into the legend.
            let cs = if text_width(c, s) + 16 > plot_w as i64 {
                1
            } else {
                s
            };
            draw_label(&mut img, 8, 14 + text_height(s), c, cs, BLACK);
        }
    }
    if let Some(sc) = &scale {
        draw_scale(&mut img, plot_w as i64, sc);
    }
    img
}
