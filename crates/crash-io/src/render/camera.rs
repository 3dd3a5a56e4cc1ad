//! Orthographic camera: a view direction, an up hint and the visible half extents.
//! Auto views fit a bounding box from a fixed 3/4 view, so every picture of one run
//! can share the same camera.

use crate::frame::Frame;
use crash_core::Vec3;

/// What a picture looks at, in world units (metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// World point at the centre of the picture.
    pub target: Vec3,
    /// Unit vector from the target toward the viewer.
    pub direction: Vec3,
    /// World "up" hint (projected to the picture's vertical).
    pub up: Vec3,
    /// Half of the visible width and height [m]; the picture keeps the aspect ratio.
    pub half_width: f64,
    pub half_height: f64,
}

/// Azimuth and elevation of the standard 3/4 view (z up, looking from -y, +x side).
const AZIMUTH_DEG: f64 = 35.0;
const ELEVATION_DEG: f64 = 28.0;
/// Empty border around fitted content (fraction of the half extents).
const MARGIN: f64 = 1.06;

impl View {
    /// The 3/4 view direction (from the target toward the viewer), z up.
    pub fn three_quarter_direction() -> Vec3 {
        let (a, e) = (AZIMUTH_DEG.to_radians(), ELEVATION_DEG.to_radians());
        Vec3::new(a.sin() * e.cos(), -a.cos() * e.cos(), e.sin())
    }

    /// Fit the box [lo, hi] seen from `direction` (all eight corners visible).
    pub fn fit_box(lo: Vec3, hi: Vec3, direction: Vec3, up: Vec3) -> View {
        let mut fit = Fit::new(direction, up);
        for k in 0..8 {
            fit.add(&Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ));
        }
        fit.view().unwrap_or(View {
            target: 0.5 * (lo + hi),
            direction: direction.normalize(),
            up,
            half_width: 1.0,
            half_height: 1.0,
        })
    }

    /// 3/4 view fitted tightly to every node of `frames` (None when they hold no nodes).
    pub fn fit_frames<'a>(frames: impl IntoIterator<Item = &'a Frame>) -> Option<View> {
        let mut fit = Fit::three_quarter();
        for f in frames {
            fit.add_frame(f);
        }
        fit.view()
    }

    /// Grow the half extents by `f` (2 = twice as much around the target).
    pub fn widen(mut self, f: f64) -> View {
        self.half_width *= f;
        self.half_height *= f;
        self
    }

    /// Picture axes in world coordinates: right, up, and forward (into the picture).
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let f = -self.direction.normalize();
        let mut hint = self.up;
        if f.cross(&hint).norm() < 1e-9 * hint.norm().max(1e-300) {
            hint = if f.z.abs() < 0.9 {
                Vec3::z()
            } else {
                Vec3::y()
            };
        }
        let r = f.cross(&hint).normalize();
        let u = r.cross(&f);
        (r, u, f)
    }
}

/// Accumulates the extents of points seen from a fixed direction, to fit a view to
/// many frames without keeping them.
#[derive(Debug, Clone, Copy)]
pub struct Fit {
    base: View,
    right: Vec3,
    up: Vec3,
    fwd: Vec3,
    /// min/max along right, up, forward.
    lo: Vec3,
    hi: Vec3,
}

impl Fit {
    pub fn new(direction: Vec3, up: Vec3) -> Self {
        let base = View {
            target: Vec3::zeros(),
            direction: direction.normalize(),
            up,
            half_width: 1.0,
            half_height: 1.0,
        };
        let (right, up, fwd) = base.basis();
        Self {
            base,
            right,
            up,
            fwd,
            lo: Vec3::repeat(f64::INFINITY),
            hi: Vec3::repeat(f64::NEG_INFINITY),
        }
    }

    /// The standard 3/4 view, z up.
    pub fn three_quarter() -> Self {
        Self::new(View::three_quarter_direction(), Vec3::z())
    }

    /// Take in another fit of the same view (`add` over both point sets: min and max
    /// are exact, so the order does not matter).
    pub fn merge(&mut self, other: &Fit) {
        self.lo = self.lo.inf(&other.lo);
        self.hi = self.hi.sup(&other.hi);
    }

    pub fn add(&mut self, p: &Vec3) {
        if p.iter().all(|c| c.is_finite()) {
            let q = Vec3::new(p.dot(&self.right), p.dot(&self.up), p.dot(&self.fwd));
            self.lo = self.lo.inf(&q);
            self.hi = self.hi.sup(&q);
        }
    }

    pub fn add_frame(&mut self, f: &Frame) {
        for b in &f.bodies {
            b.x.iter().for_each(|p| self.add(p));
        }
    }

    /// The fitted view (None when no point was added).
    pub fn view(&self) -> Option<View> {
        if self.lo.x > self.hi.x {
            return None;
        }
        let c = 0.5 * (self.lo + self.hi);
        let size = self.hi - self.lo;
        let floor = 1e-9 + 1e-3 * size.norm();
        Some(View {
            target: self.right * c.x + self.up * c.y + self.fwd * c.z,
            half_width: (0.5 * size.x * MARGIN).max(floor),
            half_height: (0.5 * size.y * MARGIN).max(floor),
            ..self.base
        })
    }
}

/// Maps world points to pixels of a viewport (x right, y down) with a depth.
#[derive(Debug, Clone, Copy)]
pub struct Projector {
    right: Vec3,
    up: Vec3,
    fwd: Vec3,
    target: Vec3,
    scale: f64,
    cx: f64,
    cy: f64,
}

impl Projector {
    /// Viewport: left, top, width, height in pixels.
    pub fn new(view: &View, viewport: (f64, f64, f64, f64)) -> Self {
        let (x0, y0, w, h) = viewport;
        let (right, up, fwd) = view.basis();
        let scale = (w / (2.0 * view.half_width)).min(h / (2.0 * view.half_height));
        Self {
            right,
            up,
            fwd,
            target: view.target,
            scale,
            cx: x0 + 0.5 * w,
            cy: y0 + 0.5 * h,
        }
    }

    /// (pixel x, pixel y, depth); larger depth is farther away.
    pub fn project(&self, p: &Vec3) -> (f64, f64, f64) {
        let d = p - self.target;
        (
            self.cx + self.scale * d.dot(&self.right),
            self.cy - self.scale * d.dot(&self.up),
            d.dot(&self.fwd),
        )
    }

    /// Picture axes (right, up, forward).
    pub fn axes(&self) -> (Vec3, Vec3, Vec3) {
        (self.right, self.up, self.fwd)
    }
}
