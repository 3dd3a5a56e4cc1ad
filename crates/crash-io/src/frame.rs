//! A snapshot of every body at one time: what one .vtu file and one picture show.

use crash_core::{Body, Vec3};
use serde::{Deserialize, Serialize};

/// One body in a frame. Element arrays hold triangles first, then quads (the order of
/// `Body::resultants`), and so do the cells of the .vtu file.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameBody {
    pub id: u32,
    pub name: String,
    /// Shell thickness [m].
    pub thickness: f64,
    /// Current positions [m].
    pub x: Vec<Vec3>,
    /// Initial positions [m].
    pub x0: Vec<Vec3>,
    /// Nodal velocities [m/s].
    pub v: Vec<Vec3>,
    /// Nodal angular velocities [rad/s].
    pub w: Vec<Vec3>,
    pub tris: Vec<[u32; 3]>,
    pub quads: Vec<[u32; 4]>,
    /// von Mises stress at the top (+t/2) and bottom (-t/2) surface per element [Pa].
    pub von_mises_top: Vec<f64>,
    pub von_mises_bottom: Vec<f64>,
    /// Membrane forces (Nxx, Nyy, Nxy) per element [N/m], element frame.
    pub n: Vec<[f64; 3]>,
    /// Bending moments (Mxx, Myy, Mxy) per element [N m/m], element frame.
    pub m: Vec<[f64; 3]>,
    /// Contact force per node [N] (zeros when the body has none).
    pub f_contact: Vec<Vec3>,
    /// Where the body was computed when the frame was taken (set by the master, which
    /// knows the placement; None elsewhere): the worker index and the group (named by
    /// its smallest body id). Written as the cell fields `worker` and `group`.
    #[serde(default)]
    pub placement: Option<Placement>,
    /// For a body of a group split over workers (set by the master): the worker and the
    /// part of each element (cell fields `worker` and `part`; else `placement` holds
    /// for every element and the part is 0).
    #[serde(default)]
    pub parts: Option<PartCells>,
}

/// Where each element of a split body is computed: its part and that part's worker.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct PartCells {
    pub worker: Vec<u32>,
    pub part: Vec<u32>,
}

/// The worker and group of a body at one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Placement {
    pub worker: u32,
    pub group: u32,
}

impl FrameBody {
    pub fn capture(b: &Body) -> Self {
        let t = b.def.section.thickness;
        let res = b.resultants();
        let (top, bottom): (Vec<f64>, Vec<f64>) = res.iter().map(|r| r.von_mises(t)).unzip();
        let f_contact = if b.state.f_contact.len() == b.state.x.len() {
            b.state.f_contact.clone()
        } else {
            vec![Vec3::zeros(); b.state.x.len()]
        };
        Self {
            id: b.def.id,
            name: b.def.name.clone(),
            thickness: t,
            x: b.state.x.clone(),
            x0: b.def.x0.clone(),
            v: b.state.v.clone(),
            w: b.state.w.clone(),
            tris: b.def.tris.iter().map(|e| e.nodes).collect(),
            quads: b.def.quads.iter().map(|e| e.nodes).collect(),
            von_mises_top: top,
            von_mises_bottom: bottom,
            n: res.iter().map(|r| r.n).collect(),
            m: res.iter().map(|r| r.m).collect(),
            f_contact,
            placement: None,
            parts: None,
        }
    }

    pub fn element_count(&self) -> usize {
        self.tris.len() + self.quads.len()
    }

    /// Larger of the top and bottom von Mises stress of element `e`.
    pub fn von_mises_max(&self, e: usize) -> f64 {
        self.von_mises_top[e].max(self.von_mises_bottom[e])
    }
}

/// All bodies at one time, sorted by body id.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Simulated time [s].
    pub time: f64,
    pub step: u64,
    pub bodies: Vec<FrameBody>,
}

impl Frame {
    /// Snapshot of the given bodies, in any order (gathered from several workers).
    pub fn capture(time: f64, step: u64, bodies: &[&Body]) -> Self {
        Self::from_bodies(
            time,
            step,
            bodies.iter().map(|b| FrameBody::capture(b)).collect(),
        )
    }

    /// Frame from already captured bodies (any order; sorted by id here).
    pub fn from_bodies(time: f64, step: u64, mut bodies: Vec<FrameBody>) -> Self {
        bodies.sort_by_key(|b| b.id);
        Self { time, step, bodies }
    }

    pub fn node_count(&self) -> usize {
        self.bodies.iter().map(|b| b.x.len()).sum()
    }

    /// The state hash of the bodies in the frame (the same value as
    /// `crash_core::hash::state_hash` of the bodies it was captured from).
    pub fn state_hash(&self) -> u64 {
        crash_core::hash::state_hash_of(
            self.bodies
                .iter()
                .map(|b| (b.id, &b.x[..], &b.v[..], &b.w[..])),
        )
    }

    pub fn element_count(&self) -> usize {
        self.bodies.iter().map(|b| b.element_count()).sum()
    }

    /// Axis-aligned bounds of all current positions (None for an empty frame).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self.bodies.iter().flat_map(|b| b.x.iter());
        let first = *it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p))))
    }

    /// Largest element von Mises stress (top or bottom) in the frame.
    pub fn max_von_mises(&self) -> f64 {
        self.bodies
            .iter()
            .flat_map(|b| (0..b.element_count()).map(move |e| b.von_mises_max(e)))
            .filter(|s| s.is_finite())
            .fold(0.0, f64::max)
    }
}
