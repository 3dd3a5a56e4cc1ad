//! Pipeline stage: element internal forces, in parallel over fixed-size chunks of
//! elements into per-element slots (no shared accumulation: thread-count independent).

use crate::body::{Body, BodyDef};
use crate::element::batch::{ChunkResult, QuadChunk, TriChunk};
use crate::element::simd::dispatch;
use crate::element::{
    ElemEnergy, ElemFailure, HourglassState, QuadElem, ShellState, Slot, TriElem,
};
use crate::error::Fault;
use crate::material::Section;
use rayon::prelude::*;

/// The element time step is the membrane estimate L_e / c times this factor: the
/// membrane estimate ignores the transverse-shear, drilling and hourglass stiffness,
/// which on elongated cells and on corner nodes held by one element lift the highest
/// frequency above it (power iteration measured omega_max L_e/(2c) up to 1.06 for
/// triangles, 0.995 for quads: tests/stability.rs).
pub const DT_SHAPE: f64 = 0.8;

/// Critical time step of an element of characteristic length `length` (no safety
/// factor): DT_SHAPE L / c, reduced for Kelvin damping.
pub fn element_dt(sec: &Section, length: f64) -> f64 {
    DT_SHAPE * length / sec.wave_speed * sec.damping_factor(length)
}

/// Elements per parallel task. Fixed, so that per-chunk partial sums (and therefore the
/// totals) are identical for any number of threads.
pub const CHUNK: usize = 256;

// The parallel loops over chunks are split down to single chunks (`with_max_len(1)`):
// rayon otherwise cuts a loop into two pieces per thread and splits a piece further only
// when another thread steals it, so a loop of a few dozen chunks (the showcase's sphere
// has 80, its plate 15) can end with one thread finishing a piece of 10-20 chunks alone
// (docs/performance-history.md, session 9). Which thread runs a chunk never changes its result.

/// Whether the element loop of a body whose per-cycle data (reference data, resultant
/// states and force slots) take `bytes` writes its force slots with non-temporal stores:
/// when those data exceed the last-level cache, the slots written by a normal store (which
/// first reads each line it fills) are gone from the cache before the integration reads
/// them. `CRASH_STREAM=0|1` in the environment, read once, overrides the rule (for
/// measurements); the values written are the same either way.
pub fn stream_slots(bytes: usize) -> bool {
    static MODE: std::sync::OnceLock<Option<bool>> = std::sync::OnceLock::new();
    let mode = MODE.get_or_init(|| match std::env::var("CRASH_STREAM").as_deref() {
        Ok("0") => Some(false),
        Ok("1") => Some(true),
        _ => None,
    });
    mode.unwrap_or_else(|| bytes > last_level_cache())
}

/// The bytes the element loop of `d` reads and writes per cycle: reference data,
/// resultant states and force slots.
pub(crate) fn cycle_bytes(d: &BodyDef) -> usize {
    d.slot_count() * std::mem::size_of::<Slot>()
        + d.tris.len() * (std::mem::size_of::<TriElem>() + std::mem::size_of::<ShellState>())
        + d.quads.len()
            * (std::mem::size_of::<QuadElem>()
                + std::mem::size_of::<ShellState>()
                + std::mem::size_of::<HourglassState>())
}

/// Size of the last-level cache in bytes (Linux sysfs; 32 MiB where it cannot be read).
pub(crate) fn last_level_cache() -> usize {
    static SIZE: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *SIZE.get_or_init(|| {
        (1..8)
            .rev()
            .find_map(|i| {
                let dir = format!("/sys/devices/system/cpu/cpu0/cache/index{i}");
                let size = std::fs::read_to_string(format!("{dir}/size")).ok()?;
                let kib: usize = size.trim().strip_suffix('K')?.parse().ok()?;
                Some(kib << 10)
            })
            .unwrap_or(32 << 20)
    })
}

/// What the element loop of one body reports.
#[derive(Debug, Clone)]
pub struct ForceSums {
    pub energy: ElemEnergy,
    /// `BodyDef::uncounted`: elements whose energies another part counts.
    pub(crate) uncounted: Option<std::sync::Arc<[bool]>>,
    /// Smallest element critical time step (without the safety factor) and its element.
    pub dt: f64,
    pub dt_element: usize,
    /// Element with the largest strain energy per unit initial area (for diagnostics).
    pub hot_element: usize,
    pub hot_density: f64,
}

impl Default for ForceSums {
    fn default() -> Self {
        Self {
            energy: ElemEnergy::default(),
            uncounted: None,
            dt: f64::INFINITY,
            dt_element: 0,
            hot_element: 0,
            hot_density: 0.0,
        }
    }
}

impl ForceSums {
    /// Add element `e`: its energies, its strain energy per unit initial area
    /// (internal + hourglass) / area0 and its critical time step.
    #[inline(always)]
    pub(crate) fn add(&mut self, e: usize, internal: f64, hourglass: f64, density: f64, dt: f64) {
        if !self
            .uncounted
            .as_ref()
            .is_some_and(|u| u.get(e).copied().unwrap_or(false))
        {
            self.energy.internal += internal;
            self.energy.hourglass += hourglass;
        }
        let mut dens = density;
        if dens.is_nan() {
            dens = f64::INFINITY;
        }
        if dens > self.hot_density {
            self.hot_density = dens;
            self.hot_element = e;
        }
        if dt < self.dt {
            self.dt = dt;
            self.dt_element = e;
        }
    }

    fn merge(mut self, o: &ForceSums) -> Self {
        self.energy.internal += o.energy.internal;
        self.energy.hourglass += o.energy.hourglass;
        if o.hot_density > self.hot_density {
            self.hot_density = o.hot_density;
            self.hot_element = o.hot_element;
        }
        if o.dt < self.dt {
            self.dt = o.dt;
            self.dt_element = o.dt_element;
        }
        self
    }
}

fn to_fault(body: u32, step: u64, e: usize, f: ElemFailure) -> Fault {
    match f {
        ElemFailure::Collapsed { ratio } => Fault::Collapsed {
            step,
            body,
            element: e,
            ratio,
        },
        ElemFailure::Inverted { corner } => Fault::Inverted {
            step,
            body,
            element: e,
            corner,
        },
    }
}

impl Body {
    /// Internal forces at the current positions, updating the rate-form resultants with
    /// the half-step velocities over `h` (h = 0 at the start). Fixed/kinematic bodies
    /// compute nothing. With Kelvin damping the kernels also write the Kelvin part of
    /// every slot into the second half of `slots` (`BodyDef::slot_count`), which the
    /// integration books as dissipation.
    pub fn internal_forces(&mut self, h: f64, step: u64) -> Result<ForceSums, Fault> {
        let done = if crate::summed::wanted(&self.def) {
            self.summed_chunks(h)
        } else {
            self.no_chunks()
        };
        self.finish_forces(h, done, step)
    }

    /// Chunks of the element loop (triangles', then quads'), none computed yet.
    pub fn no_chunks(&self) -> Vec<Option<ChunkResult>> {
        let chunks = |n: usize| n.div_ceil(CHUNK);
        let n = if self.def.kinematic {
            0
        } else {
            chunks(self.def.tris.len()) + chunks(self.def.quads.len())
        };
        (0..n).map(|_| None).collect()
    }

    /// Which chunks read only the first `owned` nodes (a part's owned nodes): they can
    /// be computed before the halo nodes are current.
    pub fn chunks_within(&self, owned: usize) -> Vec<bool> {
        let inside = |nodes: &[u32]| nodes.iter().all(|&n| (n as usize) < owned);
        if self.def.kinematic {
            return Vec::new();
        }
        let tris = self.def.tris.chunks(CHUNK);
        let quads = self.def.quads.chunks(CHUNK);
        tris.map(|c| c.iter().all(|e| inside(&e.nodes)))
            .chain(quads.map(|c| c.iter().all(|e| inside(&e.nodes))))
            .collect()
    }

    /// The force slots sized for the definition: Kelvin damping given after the body was
    /// built needs the slots' Kelvin half (the node loop books the Kelvin work when the
    /// slots have it). Both element stages (`element_chunks`, `summed_chunks`) call it.
    pub(crate) fn fit_slots(&mut self) {
        let want = self.def.slot_count();
        if self.state.slots.len() < want {
            self.state.slots.resize(want, [0.0; 6]);
        }
    }

    /// Compute the element chunks not yet in `done` (`None`) and, if given, marked in
    /// `only`, in parallel, into it. Each chunk writes only its own elements' states and
    /// slots, so chunks may be computed at different times (a part's inner chunks while
    /// its halo travels).
    pub fn element_chunks(
        &mut self,
        h: f64,
        done: &mut [Option<ChunkResult>],
        only: Option<&[bool]>,
    ) {
        if self.def.kinematic {
            return;
        }
        let wanted = |k: usize| only.is_none_or(|m| m.get(k).copied().unwrap_or(false));
        if (0..done.len()).any(|k| done[k].is_none() && wanted(k)) {
            // the slots carry the forces again (`summed`)
            self.state.node_sums.clear();
        }
        let (sec, stab) = (self.def.section, self.def.stab);
        let nt = self.def.tris.len();
        let ns = self.def.gather_slot.len();
        self.fit_slots();
        let want = self.def.slot_count();
        let nodes = (&self.state.x[..], &self.state.v[..], &self.state.w[..]);
        let (slots, kelvin) = self.state.slots.split_at_mut(ns);
        let (tri_slots, quad_slots) = slots.split_at_mut(3 * nt);
        // empty unless the material is damped (a state may carry a stale Kelvin half)
        let kelvin = &mut kelvin[..want - ns];
        let (tri_kelvin, quad_kelvin) = kelvin.split_at_mut(if want > ns { 3 * nt } else { 0 });
        let (tri_state, quad_state) = self.state.shell.split_at_mut(nt);

        // each chunk runs on the SIMD path of this CPU (element::simd)
        let uncounted = &self.def.uncounted;
        let stream = stream_slots(cycle_bytes(&self.def));
        let tri = |ci: usize,
                   els: &[TriElem],
                   states: &mut [ShellState],
                   slots: &mut [Slot],
                   damped: &mut [Slot]| {
            dispatch(TriChunk {
                sec: &sec,
                stab: &stab,
                els,
                states,
                slots,
                damped,
                nodes,
                h,
                first: ci * CHUNK,
                uncounted,
                stream,
            })
        };
        let n_tri = nt.div_ceil(CHUNK);
        let (tri_done, quad_done) = done.split_at_mut(n_tri);
        let tri_base = self
            .def
            .tris
            .par_chunks(CHUNK)
            .zip(tri_state.par_chunks_mut(CHUNK))
            .zip(tri_slots.par_chunks_mut(3 * CHUNK))
            .zip(tri_done.par_iter_mut())
            .enumerate();
        if tri_kelvin.is_empty() {
            tri_base
                .with_max_len(1)
                .filter(|(ci, (_, d))| d.is_none() && wanted(*ci))
                .for_each(|(ci, (((els, states), slots), d))| {
                    *d = Some(tri(ci, els, states, slots, &mut []));
                });
        } else {
            tri_base
                .zip(tri_kelvin.par_chunks_mut(3 * CHUNK))
                .with_max_len(1)
                .filter(|((ci, (_, d)), _)| d.is_none() && wanted(*ci))
                .for_each(|((ci, (((els, states), slots), d)), k)| {
                    *d = Some(tri(ci, els, states, slots, k));
                });
        }

        let quad = |ci: usize,
                    els: &[QuadElem],
                    states: &mut [ShellState],
                    hourglass: &mut [HourglassState],
                    slots: &mut [Slot],
                    damped: &mut [Slot]| {
            dispatch(QuadChunk {
                sec: &sec,
                stab: &stab,
                els,
                states,
                hourglass,
                slots,
                damped,
                nodes,
                h,
                first: nt + ci * CHUNK,
                uncounted,
                stream,
            })
        };
        let quad_base = self
            .def
            .quads
            .par_chunks(CHUNK)
            .zip(quad_state.par_chunks_mut(CHUNK))
            .zip(self.state.hourglass.par_chunks_mut(CHUNK))
            .zip(quad_slots.par_chunks_mut(4 * CHUNK))
            .zip(quad_done.par_iter_mut())
            .enumerate();
        if quad_kelvin.is_empty() {
            quad_base
                .with_max_len(1)
                .filter(|(ci, (_, d))| d.is_none() && wanted(n_tri + *ci))
                .for_each(|(ci, ((((els, states), hg), slots), d))| {
                    *d = Some(quad(ci, els, states, hg, slots, &mut []));
                });
        } else {
            quad_base
                .zip(quad_kelvin.par_chunks_mut(4 * CHUNK))
                .with_max_len(1)
                .filter(|((ci, (_, d)), _)| d.is_none() && wanted(n_tri + *ci))
                .for_each(|((ci, ((((els, states), hg), slots), d)), k)| {
                    *d = Some(quad(ci, els, states, hg, slots, k));
                });
        }
    }

    /// The element loop: the chunks not yet in `done`, then the sums of every chunk's
    /// result in chunk order (so the same bits whenever each chunk was computed); the
    /// first failing chunk's fault.
    pub fn finish_forces(
        &mut self,
        h: f64,
        mut done: Vec<Option<ChunkResult>>,
        step: u64,
    ) -> Result<ForceSums, Fault> {
        if self.def.kinematic {
            self.state.internal_now = 0.0;
            self.state.hourglass_now = 0.0;
            return Ok(ForceSums::default());
        }
        self.element_chunks(h, &mut done, None);
        let mut total = ForceSums::default();
        for r in done.iter().flatten() {
            match r {
                Ok(s) => total = total.merge(s),
                Err((e, f)) => return Err(to_fault(self.def.id, step, *e, *f)),
            }
        }
        let en = &total.energy;
        if !(en.internal.is_finite() && en.hourglass.is_finite()) {
            return Err(Fault::NonFinite {
                step,
                body: self.def.id,
                place: format!("element {}", total.hot_element),
                what: "internal energy",
            });
        }
        self.state.internal_now = en.internal;
        self.state.hourglass_now = en.hourglass;
        Ok(total)
    }
}
