//! Element loops in SIMD batches: gather the node data, reference data and resultants of
//! `S::W` consecutive elements into lanes, run the kernel once for all of them, scatter
//! the resultants and force slots back; the remainder of a chunk runs one element at a
//! time (`S = f64`). The arithmetic per element is the same for any lane count, so the
//! results do not depend on the SIMD path (`simd`) nor on the chunking.

use super::plate::{Consts, ShellL};
use super::quad::{quad_kernel, HgL, QuadElem, QuadIn};
use super::real::{Lanes, Real, V3};
use super::simd::Lanewise;
use super::tri::{tri_kernel, KernelOut, TriElem, TriIn};
use super::{ElemFailure, HourglassState, ShellState, Slot, Stabilization, COLLAPSE_RATIO};
use crate::forces::{ForceSums, DT_SHAPE};
use crate::material::Section;
use crate::Vec3;

/// Nodal positions, half-step velocities and angular velocities of a body.
pub type Nodes<'a> = (&'a [Vec3], &'a [Vec3], &'a [Vec3]);

/// What a chunk reports: its sums, or the first failing element (body-wide index).
pub type ChunkResult = Result<ForceSums, (usize, ElemFailure)>;

/// Build a kernel scalar from W per-lane values.
#[inline(always)]
fn lanes<S: Lanes>(f: impl Fn(usize) -> f64) -> S {
    let mut s = S::splat(0.0);
    for k in 0..S::W {
        s.set_lane(k, f(k));
    }
    s
}

/// Gather x, v and w of one element node for every lane.
#[inline(always)]
fn node_vecs<S: Lanes>((x, v, w): Nodes<'_>, node: impl Fn(usize) -> u32) -> [V3<S>; 3] {
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

/// `forces::element_dt` in lanes (the same operations).
#[inline(always)]
fn element_dt<S: Real>(sec: &Section, length: S) -> S {
    let dt = S::splat(DT_SHAPE) * length / S::splat(sec.wave_speed);
    let a = sec.material.kelvin;
    if a == 0.0 {
        return dt; // damping_factor = 1
    }
    let xi = S::splat(a * sec.wave_speed) / length;
    dt * ((S::splat(1.0) + xi * xi).sqrt() - xi)
}

/// Check every lane for collapse, then add its energies and time step to the sums.
#[inline(always)]
fn book<S: Lanes>(
    sec: &Section,
    r: &KernelOut<S>,
    hourglass: S,
    area0: S,
    e0: usize,
    sums: &mut ForceSums,
) -> Result<(), (usize, ElemFailure)> {
    for l in 0..S::W {
        let ratio = r.ratio.lane(l);
        if ratio.is_nan() || ratio < COLLAPSE_RATIO {
            return Err((e0 + l, ElemFailure::Collapsed { ratio }));
        }
    }
    let dt = element_dt(sec, r.length);
    let density = (r.internal + hourglass) / area0;
    for l in 0..S::W {
        sums.add(
            e0 + l,
            r.internal.lane(l),
            hourglass.lane(l),
            r.damping.lane(l),
            density.lane(l),
            dt.lane(l),
        );
    }
    Ok(())
}

/// Triangles `els` (exactly S::W of them) starting at element index `e0`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn tri_batch<S: Lanes>(
    k: &Consts<S>,
    sec: &Section,
    els: &[TriElem],
    e0: usize,
    nodes: Nodes<'_>,
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
    book(sec, &r, S::splat(0.0), input.area0, e0, sums)?;
    shell_out(&st, sts);
    slots_out(&out, slots);
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
    nodes: Nodes<'_>,
    h: S,
    sts: &mut [ShellState],
    hgs: &mut [HourglassState],
    slots: &mut [Slot],
    sums: &mut ForceSums,
) -> Result<(), (usize, ElemFailure)> {
    let g: [[V3<S>; 3]; 4] = std::array::from_fn(|i| node_vecs(nodes, |l| els[l].nodes[i]));
    let input = QuadIn {
        x: std::array::from_fn(|i| g[i][0]),
        v: std::array::from_fn(|i| g[i][1]),
        w: std::array::from_fn(|i| g[i][2]),
        bx0: std::array::from_fn(|i| lanes(|l| els[l].bx0[2 + i])),
        by0: std::array::from_fn(|i| lanes(|l| els[l].by0[2 + i])),
        gamma: std::array::from_fn(|i| lanes(|l| els[l].gamma[i])),
        area0: lanes(|l| els[l].area0),
        e0: std::array::from_fn(|i| lanes(|l| els[l].e0[i])),
        k_m: lanes(|l| els[l].k_m),
        k_w: lanes(|l| els[l].k_w),
        k_th: lanes(|l| els[l].k_th),
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
    book(sec, &r, extra.hourglass, input.area0, e0, sums)?;
    shell_out(&st, sts);
    for (l, s) in hgs.iter_mut().enumerate().take(S::W) {
        s.w = hg.w.lane(l);
        s.th = hg.th.map(|c| c.lane(l));
    }
    slots_out(&out, slots);
    Ok(())
}

/// One chunk of triangles: forces into `slots` (3 per element), resultants updated.
#[derive(Debug)]
pub struct TriChunk<'a> {
    pub sec: &'a Section,
    pub stab: &'a Stabilization,
    pub els: &'a [TriElem],
    pub states: &'a mut [ShellState],
    pub slots: &'a mut [Slot],
    pub nodes: Nodes<'a>,
    pub h: f64,
    /// Body-wide index of the chunk's first element.
    pub first: usize,
}

impl Lanewise for TriChunk<'_> {
    type Output = ChunkResult;

    #[inline(always)]
    fn run<S: Lanes>(self) -> ChunkResult {
        let (kw, k1) = (
            Consts::<S>::new(self.sec, self.stab),
            Consts::<f64>::new(self.sec, self.stab),
        );
        let (els, sts, slots) = (self.els, self.states, self.slots);
        let mut sums = ForceSums::default();
        let w = S::W;
        let full = els.len() - els.len() % w;
        let mut j = 0;
        while j < full {
            tri_batch(
                &kw,
                self.sec,
                &els[j..j + w],
                self.first + j,
                self.nodes,
                S::splat(self.h),
                &mut sts[j..],
                &mut slots[3 * j..],
                &mut sums,
            )?;
            j += w;
        }
        while j < els.len() {
            tri_batch(
                &k1,
                self.sec,
                &els[j..j + 1],
                self.first + j,
                self.nodes,
                self.h,
                &mut sts[j..],
                &mut slots[3 * j..],
                &mut sums,
            )?;
            j += 1;
        }
        Ok(sums)
    }
}

/// One chunk of quads: forces into `slots` (4 per element), resultants updated.
#[derive(Debug)]
pub struct QuadChunk<'a> {
    pub sec: &'a Section,
    pub stab: &'a Stabilization,
    pub els: &'a [QuadElem],
    pub states: &'a mut [ShellState],
    pub hourglass: &'a mut [HourglassState],
    pub slots: &'a mut [Slot],
    pub nodes: Nodes<'a>,
    pub h: f64,
    /// Body-wide index of the chunk's first element.
    pub first: usize,
}

impl Lanewise for QuadChunk<'_> {
    type Output = ChunkResult;

    #[inline(always)]
    fn run<S: Lanes>(self) -> ChunkResult {
        let (kw, k1) = (
            Consts::<S>::new(self.sec, self.stab),
            Consts::<f64>::new(self.sec, self.stab),
        );
        let (els, sts, hgs, slots) = (self.els, self.states, self.hourglass, self.slots);
        let mut sums = ForceSums::default();
        let w = S::W;
        let full = els.len() - els.len() % w;
        let mut j = 0;
        while j < full {
            quad_batch(
                &kw,
                self.sec,
                &els[j..j + w],
                self.first + j,
                self.nodes,
                S::splat(self.h),
                &mut sts[j..],
                &mut hgs[j..],
                &mut slots[4 * j..],
                &mut sums,
            )?;
            j += w;
        }
        while j < els.len() {
            quad_batch(
                &k1,
                self.sec,
                &els[j..j + 1],
                self.first + j,
                self.nodes,
                self.h,
                &mut sts[j..],
                &mut hgs[j..],
                &mut slots[4 * j..],
                &mut sums,
            )?;
            j += 1;
        }
        Ok(sums)
    }
}
