//! Z-buffered, flat-coloured triangle rasterizer with optional element edge lines.

use super::image::{Image, Rgb};

#[derive(Debug)]
pub struct Raster {
    pub image: Image,
    depth: Vec<f64>,
}

/// Triangles seen almost edge-on (smallest height below this, pixels) get no outline,
/// so silhouettes do not turn into dark bands.
const EDGE_MIN_HEIGHT: f64 = 2.0;

impl Raster {
    pub fn new(image: Image) -> Self {
        let n = image.width as usize * image.height as usize;
        Self {
            image,
            depth: vec![f64::INFINITY; n],
        }
    }

    /// Fill the triangle `p` (pixel x, pixel y, depth). `edges` marks which edges to
    /// outline (bit i: the edge opposite vertex i) with `edge_colour`, `edge_width` px.
    pub fn triangle(&mut self, p: [(f64, f64, f64); 3], colour: Rgb, edges: u8, edge: (Rgb, f64)) {
        let (w, h) = (self.image.width as f64, self.image.height as f64);
        let area = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
        if area.abs() <= 1e-12 || area.is_nan() {
            return;
        }
        let xmin = p
            .iter()
            .map(|q| q.0)
            .fold(f64::INFINITY, f64::min)
            .max(0.0)
            .floor() as i64;
        let xmax = p
            .iter()
            .map(|q| q.0)
            .fold(f64::NEG_INFINITY, f64::max)
            .min(w - 1.0)
            .ceil() as i64;
        let ymin = p
            .iter()
            .map(|q| q.1)
            .fold(f64::INFINITY, f64::min)
            .max(0.0)
            .floor() as i64;
        let ymax = p
            .iter()
            .map(|q| q.1)
            .fold(f64::NEG_INFINITY, f64::max)
            .min(h - 1.0)
            .ceil() as i64;
        // Edge lengths (edge i is opposite vertex i): pixel distance = w_i * 2A / len_i.
        let len =
            |a: usize, b: usize| ((p[a].0 - p[b].0).powi(2) + (p[a].1 - p[b].1).powi(2)).sqrt();
        let lens = [len(1, 2), len(2, 0), len(0, 1)];
        let heights = lens.map(|l| area.abs() / l.max(1e-12));
        let outline = edges != 0 && heights.iter().all(|&hgt| hgt > EDGE_MIN_HEIGHT);
        for y in ymin..=ymax {
            let py = y as f64 + 0.5;
            for x in xmin..=xmax {
                let px = x as f64 + 0.5;
                let e = |a: usize, b: usize| {
                    ((p[b].0 - p[a].0) * (py - p[a].1) - (p[b].1 - p[a].1) * (px - p[a].0)) / area
                };
                let bary = [e(1, 2), e(2, 0), e(0, 1)];
                if bary.iter().any(|&b| b < 0.0) {
                    continue;
                }
                let z = bary[0] * p[0].2 + bary[1] * p[1].2 + bary[2] * p[2].2;
                let i = y as usize * self.image.width as usize + x as usize;
                if z >= self.depth[i] {
                    continue;
                }
                self.depth[i] = z;
                let mut c = colour;
                if outline {
                    for k in 0..3 {
                        if edges & (1 << k) != 0 && bary[k] * heights[k] < edge.1 {
                            c = edge.0;
                        }
                    }
                }
                self.image.put(x, y, c);
            }
        }
    }
}
