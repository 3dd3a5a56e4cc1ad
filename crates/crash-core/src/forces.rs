//! Pipeline stage: element internal forces, in parallel over fixed-size chunks of
//! elements into per-element slots (no shared accumulation: thread-count independent).

use crate::body::Body;
use crate::element::quad::quad_forces;
use crate::element::tri::tri_forces;
use crate::element::{ElemEnergy, ElemFailure, Slot};
use crate::error::Fault;
use crate::Vec3;
use rayon::prelude::*;

/// Elements per parallel task. Fixed, so that per-chunk partial sums (and therefore the
/// totals) are identical for any number of threads.
pub const CHUNK: usize = 256;

/// What the element loop of one body reports.
#[derive(Debug, Clone, Copy)]
pub struct ForceSums {
    pub energy: ElemEnergy,
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
            dt: f64::INFINITY,
            dt_element: 0,
            hot_element: 0,
            hot_density: 0.0,
        }
    }
}

impl ForceSums {
    fn add(&mut self, e: usize, en: &ElemEnergy, area0: f64, dt: f64) {
        self.energy.internal += en.internal;
        self.energy.hourglass += en.hourglass;
        self.energy.damping += en.damping;
        let mut dens = (en.internal + en.hourglass) / area0;
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
        self.energy.damping += o.energy.damping;
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

type ChunkResult = Result<ForceSums, (usize, ElemFailure)>;

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

#[inline(always)]
fn pick<const N: usize>(a: &[Vec3], nodes: &[u32; N]) -> [Vec3; N] {
    nodes.map(|n| a[n as usize])
}

impl Body {
    /// Internal forces at the current positions, updating the rate-form resultants with
    /// the half-step velocities over `h` (h = 0 at the start). Fixed/kinematic bodies
    /// compute nothing.
    pub fn internal_forces(&mut self, h: f64, step: u64) -> Result<ForceSums, Fault> {
        if self.kinematic {
            self.internal_now = 0.0;
            self.hourglass_now = 0.0;
            return Ok(ForceSums::default());
        }
        let sec = self.section;
        let stab = self.stab;
        let c = sec.wave_speed;
        let (x, v, w) = (&self.x, &self.v, &self.w);
        let nt = self.tris.len();
        let (tri_slots, quad_slots) = self.slots.split_at_mut(3 * nt);
        let (tri_state, quad_state) = self.shell.split_at_mut(nt);

        let tri_chunks: Vec<ChunkResult> = self
            .tris
            .par_chunks(CHUNK)
            .zip(tri_state.par_chunks_mut(CHUNK))
            .zip(tri_slots.par_chunks_mut(3 * CHUNK))
            .enumerate()
            .map(|(ci, ((els, sts), slots))| {
                let mut sums = ForceSums::default();
                for (k, el) in els.iter().enumerate() {
                    let e = ci * CHUNK + k;
                    let mut en = ElemEnergy::default();
                    let out: &mut [Slot; 3] = (&mut slots[3 * k..3 * k + 3])
                        .try_into()
                        .map_err(|_| (e, ElemFailure::Collapsed { ratio: f64::NAN }))?;
                    let len = tri_forces(
                        &sec,
                        &stab,
                        el,
                        &pick(x, &el.nodes),
                        &pick(v, &el.nodes),
                        &pick(w, &el.nodes),
                        h,
                        &mut sts[k],
                        out,
                        &mut en,
                    )
                    .map_err(|f| (e, f))?;
                    sums.add(e, &en, el.area0, len / c * sec.damping_factor(len));
                }
                Ok(sums)
            })
            .collect();

        let quad_chunks: Vec<ChunkResult> = self
            .quads
            .par_chunks(CHUNK)
            .zip(quad_state.par_chunks_mut(CHUNK))
            .zip(self.hourglass.par_chunks_mut(CHUNK))
            .zip(quad_slots.par_chunks_mut(4 * CHUNK))
            .enumerate()
            .map(|(ci, (((els, sts), hgs), slots))| {
                let mut sums = ForceSums::default();
                for (k, el) in els.iter().enumerate() {
                    let e = nt + ci * CHUNK + k;
                    let mut en = ElemEnergy::default();
                    let out: &mut [Slot; 4] = (&mut slots[4 * k..4 * k + 4])
                        .try_into()
                        .map_err(|_| (e, ElemFailure::Collapsed { ratio: f64::NAN }))?;
                    let len = quad_forces(
                        &sec,
                        &stab,
                        el,
                        &pick(x, &el.nodes),
                        &pick(v, &el.nodes),
                        &pick(w, &el.nodes),
                        h,
                        &mut sts[k],
                        &mut hgs[k],
                        out,
                        &mut en,
                    )
                    .map_err(|f| (e, f))?;
                    sums.add(e, &en, el.area0, len / c * sec.damping_factor(len));
                }
                Ok(sums)
            })
            .collect();

        let mut total = ForceSums::default();
        for r in tri_chunks.iter().chain(quad_chunks.iter()) {
            match r {
                Ok(s) => total = total.merge(s),
                Err((e, f)) => return Err(to_fault(self.id, step, *e, *f)),
            }
        }
        let en = &total.energy;
        if !(en.internal.is_finite() && en.hourglass.is_finite()) {
            return Err(Fault::NonFinite {
                step,
                body: self.id,
                place: format!("element {}", total.hot_element),
                what: "internal energy",
            });
        }
        self.internal_now = en.internal;
        self.hourglass_now = en.hourglass;
        self.energy.damping += en.damping;
        Ok(total)
    }
}
