//! An RGB8 image with the few drawing primitives pictures and plots need, and PNG output.

use crate::error::{AtPath, IoError};
use std::path::Path;

pub type Rgb = [u8; 3];

pub const WHITE: Rgb = [255, 255, 255];
pub const BLACK: Rgb = [0, 0, 0];

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// Row-major RGB bytes, top row first.
    pub rgb: Vec<u8>,
}

impl Image {
    pub fn new(width: u32, height: u32, fill: Rgb) -> Self {
        let n = width as usize * height as usize;
        let mut rgb = Vec::with_capacity(3 * n);
        for _ in 0..n {
            rgb.extend_from_slice(&fill);
        }
        Self { width, height, rgb }
    }

    pub fn get(&self, x: u32, y: u32) -> Rgb {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// Set a pixel; coordinates outside the image are ignored.
    pub fn put(&mut self, x: i64, y: i64, c: Rgb) {
        if x >= 0 && y >= 0 && x < self.width as i64 && y < self.height as i64 {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            self.rgb[i..i + 3].copy_from_slice(&c);
        }
    }

    /// Blend colour `c` over a pixel with coverage `a` in [0, 1].
    pub fn blend(&mut self, x: i64, y: i64, c: Rgb, a: f64) {
        if x >= 0 && y >= 0 && x < self.width as i64 && y < self.height as i64 {
            let a = a.clamp(0.0, 1.0);
            let i = 3 * (y as usize * self.width as usize + x as usize);
            for (dst, &src) in self.rgb[i..i + 3].iter_mut().zip(&c) {
                let old = *dst as f64;
                *dst = (old + (src as f64 - old) * a).round() as u8;
            }
        }
    }

    pub fn fill_rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        for yy in y..y + h {
            for xx in x..x + w {
                self.put(xx, yy, c);
            }
        }
    }

    /// One-pixel rectangle outline.
    pub fn stroke_rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        self.fill_rect(x, y, w, 1, c);
        self.fill_rect(x, y + h - 1, w, 1, c);
        self.fill_rect(x, y, 1, h, c);
        self.fill_rect(x + w - 1, y, 1, h, c);
    }

    /// Anti-aliased line of the given width (pixels), as a chain of soft discs.
    pub fn line(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), width: f64, c: Rgb) {
        let len = ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
        let r = 0.5 * width;
        let (lx, hx) = (x0.min(x1) - r - 1.0, x0.max(x1) + r + 1.0);
        let (ly, hy) = (y0.min(y1) - r - 1.0, y0.max(y1) + r + 1.0);
        let (lx, ly) = (lx.max(-1.0).floor() as i64, ly.max(-1.0).floor() as i64);
        let hx = hx.min(self.width as f64).ceil() as i64;
        let hy = hy.min(self.height as f64).ceil() as i64;
        for py in ly..=hy {
            for px in lx..=hx {
                // Distance from the pixel centre to the segment.
                let (qx, qy) = (px as f64 + 0.5, py as f64 + 0.5);
                let t = if len > 0.0 {
                    (((qx - x0) * (x1 - x0) + (qy - y0) * (y1 - y0)) / (len * len)).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let d =
                    ((qx - x0 - t * (x1 - x0)).powi(2) + (qy - y0 - t * (y1 - y0)).powi(2)).sqrt();
                let a = (r + 0.5 - d).clamp(0.0, 1.0);
                if a > 0.0 {
                    self.blend(px, py, c, a);
                }
            }
        }
    }

    /// Copy `src` into this image with its top-left corner at (x, y).
    pub fn paste(&mut self, src: &Image, x: i64, y: i64) {
        for sy in 0..src.height {
            for sx in 0..src.width {
                self.put(x + sx as i64, y + sy as i64, src.get(sx, sy));
            }
        }
    }

    /// Average `f` x `f` blocks (supersampling resolve).
    pub fn downsample(&self, f: u32) -> Image {
        let (w, h) = (self.width / f, self.height / f);
        let mut out = Image::new(w, h, WHITE);
        let n = f * f;
        for y in 0..h {
            for x in 0..w {
                let mut acc = [0u32; 3];
                for dy in 0..f {
                    for dx in 0..f {
                        let p = self.get(x * f + dx, y * f + dy);
                        for (a, v) in acc.iter_mut().zip(p) {
                            *a += v as u32;
                        }
                    }
                }
                out.put(x as i64, y as i64, acc.map(|a| ((a + n / 2) / n) as u8));
            }
        }
        out
    }

    /// Number of distinct colours (a test and sanity measure).
    pub fn distinct_colours(&self) -> usize {
        let mut set = std::collections::HashSet::new();
        for p in self.rgb.chunks_exact(3) {
            set.insert([p[0], p[1], p[2]]);
        }
        set.len()
    }

    /// Encode as PNG (8-bit RGB).
    pub fn encode_png(&self) -> Result<Vec<u8>, png::EncodingError> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header()?;
            w.write_image_data(&self.rgb)?;
            w.finish()?;
        }
        Ok(out)
    }

    /// Save as PNG (atomically).
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), IoError> {
        let path = path.as_ref();
        let bytes = self.encode_png().map_err(|e| IoError::Png {
            path: path.to_path_buf(),
            what: e.to_string(),
        })?;
        crate::atomic::write_atomic(path, |w| w.write_all(&bytes)).map_err(|e| match e {
            IoError::Io { source, .. } => IoError::io(path, source),
            other => other,
        })?;
        Ok(())
    }
}

/// Decode a PNG file into an RGB image (RGB or RGBA 8-bit).
pub fn load_png(path: impl AsRef<Path>) -> Result<Image, IoError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).at(path)?;
    let err = |e: png::DecodingError| IoError::Png {
        path: path.to_path_buf(),
        what: e.to_string(),
    };
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .map_err(err)?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).map_err(err)?;
    let (w, h) = (info.width, info.height);
    let channels = match (info.color_type, info.bit_depth) {
        (png::ColorType::Rgb, png::BitDepth::Eight) => 3,
        (png::ColorType::Rgba, png::BitDepth::Eight) => 4,
        (c, d) => {
            return Err(IoError::Png {
                path: path.to_path_buf(),
                what: format!("unsupported colour type {c:?} / depth {d:?}"),
            })
        }
    };
    let rgb = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok(Image {
        width: w,
        height: h,
        rgb,
    })
}
