//! A snapshot of every body at one time: what one .vtu file and one picture show.

use crash_core::body::BodyDef;
use crash_core::output::{resultants_of, Resultants};
use crash_core::{Body, Vec3};
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::sync::Mutex;

/// Frame bodies whose arrays a consumer (the frame writer, a wire encoder) has finished
/// with, kept for the next capture to fill. At most `MAX_SPARE`: the writer holds at
/// most two frames in flight, so the steady state is about one frame's bodies.
static SPARE: Mutex<Vec<FrameBody>> = Mutex::new(Vec::new());
const MAX_SPARE: usize = 64;

/// Give a consumed body's arrays back for a later capture.
pub fn recycle(b: FrameBody) {
    let mut spare = SPARE.lock().unwrap_or_else(|p| p.into_inner());
    if spare.len() < MAX_SPARE {
        spare.push(b);
    }
}

/// A spare body for body `id`: its own last one if kept (same sizes), else any.
fn spare(id: u32) -> FrameBody {
    let mut spare = SPARE.lock().unwrap_or_else(|p| p.into_inner());
    let k = spare.iter().position(|b| b.id == id);
    match k {
        Some(k) => spare.swap_remove(k),
        None => spare.pop().unwrap_or_default(),
    }
}

fn refill<T: Copy>(dst: &mut Vec<T>, src: &[T]) {
    dst.clear();
    dst.extend_from_slice(src);
}

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
    /// Set by `capture_deferred`: the definition that the initial positions, the
    /// connectivity, the membrane forces `n` and the von Mises stresses still have to be
    /// derived from (`complete`), away from the step loop. None: every array is filled.
    #[serde(skip)]
    pub pending: Option<Pending>,
}

/// The definition a deferred capture derives its element arrays from.
#[derive(Debug, Clone)]
pub struct Pending(Arc<BodyDef>);

impl PartialEq for Pending {
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.0, &o.0)
    }
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
    /// The body now. The arrays come from a body the writer has finished with
    /// (`recycle`) when there is one: a frame of fresh vectors cost the step loop its
    /// page faults (about half of the capture, docs/performance-history.md, session 10).
    pub fn capture(b: &Body) -> Self {
        let mut f = Self::capture_deferred(b);
        f.complete();
        f
    }

    /// `capture` of what only the step loop has (positions, velocities, contact forces,
    /// bending moments); what follows from those and the definition (the initial
    /// positions and the connectivity, the membrane forces, the stresses) is left to
    /// `complete`, which a consumer (the frame writer's thread, a network worker's pool)
    /// runs: it was most of what a frame cost the step loop.
    pub fn capture_deferred(b: &Body) -> Self {
        let mut f = spare(b.def.id);
        f.fill(b);
        f
    }

    /// Derive what `capture_deferred` left (the same bits as `capture`); nothing when
    /// every array is filled.
    pub fn complete(&mut self) {
        let Some(Pending(def)) = self.pending.take() else {
            return;
        };
        refill(&mut self.x0, &def.x0);
        self.tris.clear();
        self.tris.extend(def.tris.iter().map(|e| e.nodes));
        self.quads.clear();
        self.quads.extend(def.quads.iter().map(|e| e.nodes));
        let t = self.thickness;
        let (top, bottom, n) = (
            &mut self.von_mises_top,
            &mut self.von_mises_bottom,
            &mut self.n,
        );
        let m = &self.m;
        resultants_of(
            &def,
            &self.x,
            |k| m[k],
            |r: Resultants| {
                let (vt, vb) = r.von_mises(t);
                top.push(vt);
                bottom.push(vb);
                n.push(r.n);
            },
        );
    }

    /// This body with every array filled: itself, or a completed copy of a deferred
    /// capture (for a consumer that only borrows it).
    pub fn completed(&self) -> std::borrow::Cow<'_, FrameBody> {
        if self.pending.is_none() {
            return std::borrow::Cow::Borrowed(self);
        }
        let mut c = self.clone();
        c.complete();
        std::borrow::Cow::Owned(c)
    }

    /// Overwrite every field with body `b` now, keeping the vectors' memory; what
    /// follows from the definition is left empty and pending.
    fn fill(&mut self, b: &Body) {
        let t = b.def.section.thickness;
        let s = &b.state;
        self.id = b.def.id;
        self.name.clear();
        self.name.push_str(&b.def.name);
        self.thickness = t;
        refill(&mut self.x, &s.x);
        refill(&mut self.v, &s.v);
        refill(&mut self.w, &s.w);
        self.x0.clear();
        self.tris.clear();
        self.quads.clear();
        self.von_mises_top.clear();
        self.von_mises_bottom.clear();
        self.n.clear();
        self.m.clear();
        self.m.extend(s.shell.iter().map(|e| e.m));
        if s.f_contact.len() == s.x.len() {
            refill(&mut self.f_contact, &s.f_contact);
        } else {
            self.f_contact.clear();
            self.f_contact.resize(s.x.len(), Vec3::zeros());
        }
        self.placement = None;
        self.parts = None;
        self.pending = Some(Pending(b.def.clone()));
    }

    pub fn element_count(&self) -> usize {
        match &self.pending {
            Some(Pending(def)) => def.element_count(),
            None => self.tris.len() + self.quads.len(),
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crash_core::shapes::{icosphere, plate, ElementKind};
    use crash_core::{Material, Section, Stabilization};

    fn body(id: u32, kind: ElementKind, cells: usize) -> Body {
        let mesh = plate(0.2, 0.1, cells, cells, kind);
        let sec = Section::new(Material::steel(), 0.002);
        let mut b = Body::new(id, "p", &mesh, sec, Stabilization::default()).expect("plate");
        // a bent state, so that resultants and stresses are not zero
        for (k, x) in b.state.x.iter_mut().enumerate() {
            x.z += 1e-4 * (x.x * 30.0).sin() + 1e-9 * k as f64;
        }
        b
    }

    #[test]
    fn a_capture_into_recycled_arrays_equals_a_fresh_one() {
        let a = body(3, ElementKind::Quad, 6);
        let mut fresh = FrameBody::default();
        fresh.fill(&a);
        fresh.complete();
        // spares of other bodies, larger and smaller, with placement and parts set
        let mut sphere = Body::new(
            9,
            "ball with a longer name",
            &icosphere(0.05, 2),
            Section::new(Material::steel(), 0.001),
            Stabilization::default(),
        )
        .expect("ball");
        sphere.state.f_contact = vec![Vec3::new(1.0, 2.0, 3.0); sphere.state.x.len()];
        for other in [&sphere, &body(4, ElementKind::Tri, 2)] {
            let mut s = FrameBody::capture(other);
            s.placement = Some(Placement {
                worker: 1,
                group: 2,
            });
            s.parts = Some(PartCells {
                worker: vec![1; 3],
                part: vec![2; 3],
            });
            recycle(s);
            assert_eq!(FrameBody::capture(&a), fresh);
        }
        assert!(fresh.von_mises_top.iter().any(|&s| s > 0.0));
        assert_eq!(fresh.f_contact.len(), fresh.x.len());
    }

    #[test]
    fn a_deferred_capture_completes_to_the_bodys_resultants_bit_for_bit() {
        for kind in [ElementKind::Tri, ElementKind::Quad] {
            let mut b = body(5, kind, 4);
            for (k, e) in b.state.shell.iter_mut().enumerate() {
                e.m = [1.0 + k as f64, -2.0, 0.5 * k as f64];
            }
            let mut f = FrameBody::capture_deferred(&b);
            assert!(f.pending.is_some() && f.n.is_empty() && f.von_mises_top.is_empty());
            assert!(f.x0.is_empty() && f.tris.is_empty() && f.quads.is_empty());
            assert_eq!(f.element_count(), b.element_count());
            assert_eq!(f.completed().n.len(), b.element_count());
            f.complete();
            assert!(f.pending.is_none());
            let t = b.def.section.thickness;
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let r = b.resultants();
            assert_eq!(
                bits(f.n.as_flattened()),
                bits(r.iter().flat_map(|r| r.n).collect::<Vec<_>>().as_slice())
            );
            assert_eq!(
                bits(f.m.as_flattened()),
                bits(r.iter().flat_map(|r| r.m).collect::<Vec<_>>().as_slice())
            );
            let vm: Vec<(f64, f64)> = r.iter().map(|r| r.von_mises(t)).collect();
            assert_eq!(
                bits(&f.von_mises_top),
                bits(&vm.iter().map(|v| v.0).collect::<Vec<_>>())
            );
            assert_eq!(
                bits(&f.von_mises_bottom),
                bits(&vm.iter().map(|v| v.1).collect::<Vec<_>>())
            );
            assert_eq!(f, FrameBody::capture(&b));
        }
    }
}
