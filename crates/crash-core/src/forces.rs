//! Pipeline stage: element internal forces, in parallel over fixed-size chunks of
//! elements into per-element slots (no shared accumulation: thread-count independent).

use crate::body::Body;
use crate::element::plate::{Consts, ShellL};
use crate::element::quad::{quad_kernel, HgL, QuadElem, QuadIn};
use crate::element::real::{Lanes, Real, F4, V3};
use crate::element::tri::{tri_kernel, KernelOut, TriElem, TriIn};
use crate::element::{ElemEnergy, ElemFailure, HourglassState, ShellState, Slot, COLLAPSE_RATIO};
use crate::error::Fault;
use crate::material::Section;
use crate::Vec3;
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

/// Walk `0..len` in SIMD batches of four elements, then the remainder one by one (the
/// same arithmetic per element either way): `f(first, is_batch_of_four)`.
#[inline(always)]
fn for_each_batch<E>(len: usize, mut f: impl FnMut(usize, bool) -> Result<(), E>) -> Result<(), E> {
    let full = len - len % 4;
    for j in (0..full).step_by(4) {
        f(j, true)?;
    }
    for j in full..len {
        f(j, false)?;
    }
    Ok(())
}

/// Build a kernel scalar from W per-lane values.
#[inline(always)]
fn lanes<S: Lanes>(f: impl Fn(usize) -> f64) -> S {
    let mut s = S::splat(0.0);
    for k in 0..S::W {
        s.set_lane(k, f(k));
    }
    s
}

/// Gather x, v and w of one element node for every lane (one bounds check per lane).
#[inline(always)]
fn node_vecs<S: Lanes>(
    (x, v, w): (&[Vec3], &[Vec3], &[Vec3]),
    node: impl Fn(usize) -> u32,
) -> [V3<S>; 3] {
    let z = S::splat(0.0);
    let mut out = [V3::new(z, z, z); 3];
    for k in 0..S::W {
        let i = node(k) as usize;
        for (o, a) in out.iter_mut().zip([x, v, w]) {
            let p = &a[i];
            o.x.set_lane(k, p.x);
            o.y.set_lane(k, p.y);
            o.z.set_lane(k, p.z);
        }
    }
    out
}

#[inline(always)]
fn shell_in<S: Lanes>(st: &[ShellState]) -> ShellL<S> {
    ShellL {
        m: std::array::from_fn(|c| lanes(|k| st[k].m[c])),
        q: std::array::from_fn(|c| lanes(|k| st[k].q[c])),
        drill: lanes(|k| st[k].drill),
    }
}

#[inline(always)]
fn shell_out<S: Lanes>(l: &ShellL<S>, st: &mut [ShellState]) {
    for (k, s) in st.iter_mut().enumerate().take(S::W) {
        s.m = l.m.map(|c| c.lane(k));
        s.q = l.q.map(|c| c.lane(k));
        s.drill = l.drill.lane(k);
    }
}

#[inline(always)]
fn slots_out<S: Lanes, const N: usize>(out: &[[S; 6]; N], slots: &mut [Slot]) {
    for k in 0..S::W {
        for i in 0..N {
            slots[k * N + i] = out[i].map(|c| c.lane(k));
        }
    }
}

/// Triangles `els` (exactly S::W of them) starting at element index `e0`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn tri_batch<S: Lanes>(
    k: &Consts<S>,
    sec: &Section,
    els: &[TriElem],
    e0: usize,
    nodes: (&[Vec3], &[Vec3], &[Vec3]),
    h: S,
    sts: &mut [ShellState],
    slots: &mut [Slot],
    sums: &mut ForceSums,
) -> Result<(), (usize, ElemFailure)> {
    let g: [[V3<S>; 3]; 3] = std::array::from_fn(|i| node_vecs(nodes, |l| els[l].nodes[i]));
    let input = TriIn {
        x: std::array::from_fn(|i| g[i][0]),
        v: std::array::from_fn(|i| g[i][1]),
        w: std::array::from_fn(|i| g[i][2]),
        bx0: std::array::from_fn(|i| lanes(|l| els[l].bx0[i])),
        by0: std::array::from_fn(|i| lanes(|l| els[l].by0[i])),
        area0: lanes(|l| els[l].area0),
    };
    let mut st = shell_in::<S>(sts);
    let mut out = [[S::splat(0.0); 6]; 3];
    let r = tri_kernel(k, &input, h, &mut st, &mut out);
    book(sec, &r, S::splat(0.0), e0, |l| els[l].area0, sums)?;
    shell_out(&st, sts);
    slots_out(&out, slots);
    Ok(())
}

/// Check every lane for collapse, then add its energies and time step to the sums.
#[inline(always)]
fn book<S: Lanes>(
    sec: &Section,
    r: &KernelOut<S>,
    hourglass: S,
    e0: usize,
    area0: impl Fn(usize) -> f64,
    sums: &mut ForceSums,
) -> Result<(), (usize, ElemFailure)> {
    for l in 0..S::W {
        let ratio = r.ratio.lane(l);
        if ratio.is_nan() || ratio < COLLAPSE_RATIO {
            return Err((e0 + l, ElemFailure::Collapsed { ratio }));
        }
    }
    for l in 0..S::W {
        let en = ElemEnergy {
            internal: r.internal.lane(l),
            hourglass: hourglass.lane(l),
            damping: r.damping.lane(l),
        };
        let len = r.length.lane(l);
        sums.add(e0 + l, &en, area0(l), element_dt(sec, len));
    }
    Ok(())
}

/// Quads `els` (exactly S::W of them) starting at element index `e0`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn quad_batch<S: Lanes>(
    k: &Consts<S>,
    sec: &Section,
    els: &[QuadElem],
    e0: usize,
    nodes: (&[Vec3], &[Vec3], &[Vec3]),
    h: S,
    sts: &mut [ShellState],
    hgs: &mut [HourglassState],
    slots: &mut [Slot],
    sums: &mut ForceSums,
) -> Result<(), (usize, ElemFailure)> {
    let inv = |kk: f64| if kk > 0.0 { 0.5 / kk } else { 0.0 };
    let g: [[V3<S>; 3]; 4] = std::array::from_fn(|i| node_vecs(nodes, |l| els[l].nodes[i]));
    let input = QuadIn {
        x: std::array::from_fn(|i| g[i][0]),
        v: std::array::from_fn(|i| g[i][1]),
        w: std::array::from_fn(|i| g[i][2]),
        bx0: std::array::from_fn(|i| lanes(|l| els[l].bx0[i])),
        by0: std::array::from_fn(|i| lanes(|l| els[l].by0[i])),
        gamma: std::array::from_fn(|i| lanes(|l| els[l].gamma[i])),
        area0: lanes(|l| els[l].area0),
        e0: std::array::from_fn(|i| lanes(|l| els[l].e0[i])),
        k_m: lanes(|l| els[l].k_m),
        k_w: lanes(|l| els[l].k_w),
        k_th: lanes(|l| els[l].k_th),
        hinv_w: lanes(|l| inv(els[l].k_w)),
        hinv_th: lanes(|l| inv(els[l].k_th)),
    };
    let mut st = shell_in::<S>(sts);
    let mut hg = HgL {
        w: lanes(|l| hgs[l].w),
        th: std::array::from_fn(|c| lanes(|l| hgs[l].th[c])),
    };
    let mut out = [[S::splat(0.0); 6]; 4];
    let (r, extra) = quad_kernel(k, &input, h, &mut st, &mut hg, &mut out);
    for l in 0..S::W {
        for (corner, c) in extra.corners.iter().enumerate() {
            if c.lane(l).is_nan() || c.lane(l) <= 0.0 {
                return Err((e0 + l, ElemFailure::Inverted { corner }));
            }
        }
    }
    book(sec, &r, extra.hourglass, e0, |l| els[l].area0, sums)?;
    shell_out(&st, sts);
    for (l, s) in hgs.iter_mut().enumerate().take(S::W) {
        s.w = hg.w.lane(l);
        s.th = hg.th.map(|c| c.lane(l));
    }
    slots_out(&out, slots);
    Ok(())
}

impl Body {
    /// Internal forces at the current positions, updating the rate-form resultants with
    /// the half-step velocities over `h` (h = 0 at the start). Fixed/kinematic bodies
    /// compute nothing.
    pub fn internal_forces(&mut self, h: f64, step: u64) -> Result<ForceSums, Fault> {
        if self.def.kinematic {
            self.state.internal_now = 0.0;
            self.state.hourglass_now = 0.0;
            return Ok(ForceSums::default());
        }
        let sec = self.def.section;
        let k4 = Consts::<F4>::new(&sec, &self.def.stab);
        let k1 = Consts::<f64>::new(&sec, &self.def.stab);
        let nodes = (&self.state.x[..], &self.state.v[..], &self.state.w[..]);
        let nt = self.def.tris.len();
        let (tri_slots, quad_slots) = self.state.slots.split_at_mut(3 * nt);
        let (tri_state, quad_state) = self.state.shell.split_at_mut(nt);

        let tri_chunks: Vec<ChunkResult> = self
            .def
            .tris
            .par_chunks(CHUNK)
            .zip(tri_state.par_chunks_mut(CHUNK))
            .zip(tri_slots.par_chunks_mut(3 * CHUNK))
            .enumerate()
            .map(|(ci, ((els, sts), slots))| {
                let mut sums = ForceSums::default();
                let base = ci * CHUNK;
                for_each_batch(els.len(), |j, four| {
                    let (st, sl) = (&mut sts[j..], &mut slots[3 * j..]);
                    if four {
                        tri_batch(
                            &k4,
                            &sec,
                            &els[j..j + 4],
                            base + j,
                            nodes,
                            F4::splat(h),
                            st,
                            sl,
                            &mut sums,
                        )
                    } else {
                        tri_batch(
                            &k1,
                            &sec,
                            &els[j..j + 1],
                            base + j,
                            nodes,
                            h,
                            st,
                            sl,
                            &mut sums,
                        )
                    }
                })?;
                Ok(sums)
            })
            .collect();

        let quad_chunks: Vec<ChunkResult> = self
            .def
            .quads
            .par_chunks(CHUNK)
            .zip(quad_state.par_chunks_mut(CHUNK))
            .zip(self.state.hourglass.par_chunks_mut(CHUNK))
            .zip(quad_slots.par_chunks_mut(4 * CHUNK))
            .enumerate()
            .map(|(ci, (((els, sts), hgs), slots))| {
                let mut sums = ForceSums::default();
                let base = nt + ci * CHUNK;
                for_each_batch(els.len(), |j, four| {
                    let (st, hg, sl) = (&mut sts[j..], &mut hgs[j..], &mut slots[4 * j..]);
                    if four {
                        quad_batch(
                            &k4,
                            &sec,
                            &els[j..j + 4],
                            base + j,
                            nodes,
                            F4::splat(h),
                            st,
                            hg,
                            sl,
                            &mut sums,
                        )
                    } else {
                        quad_batch(
                            &k1,
                            &sec,
                            &els[j..j + 1],
                            base + j,
                            nodes,
                            h,
                            st,
                            hg,
                            sl,
                            &mut sums,
                        )
                    }
                })?;
                Ok(sums)
            })
            .collect();

        let mut total = ForceSums::default();
        for r in tri_chunks.iter().chain(quad_chunks.iter()) {
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
        self.state.energy.damping += en.damping;
        Ok(total)
    }
}
