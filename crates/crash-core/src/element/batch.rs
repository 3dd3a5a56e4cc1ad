//! Element loops in SIMD batches: gather the node data, reference data and resultants of
//! `S::W` consecutive elements into lanes, run the kernel once for all of them, scatter
//! the resultants and force slots back; the remainder of a chunk runs one element at a
//! time (`S = f64`). The arithmetic per element is the same for any lane count, so the
//! results do not depend on the SIMD path (`simd`) nor on the chunking.

use super::plate::{Consts, ShellL};
use super::quad::{hourglass_shape, hourglass_stiffness, quad_kernel, HgL, QuadElem, QuadIn};
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

/// Lanes from per-lane values `f(0..W)`.
#[inline(always)]
fn gather<S: Lanes>(f: impl Fn(usize) -> f64) -> S {
    let mut a = [0.0; 8];
    for (k, v) in a.iter_mut().enumerate().take(S::W) {
        *v = f(k);
    }
    S::from_array(a)
}

/// One node vector of every lane: `at(k)` is lane k's node.
#[inline(always)]
fn gather_v3<S: Lanes>(a: &[Vec3], at: impl Fn(usize) -> usize) -> V3<S> {
    V3::new(
        gather(
            #[inline(always)]
            |k| a[at(k)].x,
        ),
        gather(
            #[inline(always)]
            |k| a[at(k)].y,
        ),
        gather(
            #[inline(always)]
            |k| a[at(k)].z,
        ),
    )
}

#[inline(always)]
fn gather_shell<S: Lanes>(sts: &[ShellState]) -> ShellL<S> {
    ShellL {
        m: [
            gather(|k| sts[k].m[0]),
            gather(|k| sts[k].m[1]),
            gather(|k| sts[k].m[2]),
        ],
        q: [gather(|k| sts[k].q[0]), gather(|k| sts[k].q[1])],
        drill: gather(|k| sts[k].drill),
    }
}

#[inline(always)]
fn scatter_shell<S: Lanes>(l: &ShellL<S>, sts: &mut [ShellState]) {
    let (m0, m1, m2) = (l.m[0].to_array(), l.m[1].to_array(), l.m[2].to_array());
    let (q0, q1, dr) = (l.q[0].to_array(), l.q[1].to_array(), l.drill.to_array());
    for (k, s) in sts.iter_mut().enumerate().take(S::W) {
        s.m = [m0[k], m1[k], m2[k]];
        s.q = [q0[k], q1[k]];
        s.drill = dr[k];
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
    if !r.ratio.all_above(COLLAPSE_RATIO, false) {
        let ratio = r.ratio.to_array();
        for (l, &ratio) in ratio.iter().enumerate().take(S::W) {
            if ratio.is_nan() || ratio < COLLAPSE_RATIO {
                return Err((e0 + l, ElemFailure::Collapsed { ratio }));
            }
        }
    }
    let dt = element_dt(sec, r.length).to_array();
    let density = ((r.internal + hourglass) / area0).to_array();
    let (internal, hourglass) = (r.internal.to_array(), hourglass.to_array());
    for l in 0..S::W {
        sums.add(e0 + l, internal[l], hourglass[l], density[l], dt[l]);
    }
    Ok(())
}

/// Lanes of a triangle batch: kernel input, resultants, nodal forces and their Kelvin
/// part.
#[derive(Debug, Clone, Copy)]
struct TriLanes<S> {
    input: TriIn<S>,
    st: ShellL<S>,
    out: [[S; 6]; 3],
    out_d: [[S; 6]; 3],
}

impl<S: Real> TriLanes<S> {
    fn zero() -> Self {
        let z = S::splat(0.0);
        let z3 = V3::new(z, z, z);
        Self {
            input: TriIn {
                x: [z3; 3],
                v: [z3; 3],
                w: [z3; 3],
                bx0: [z; 3],
                by0: [z; 3],
                area0: z,
            },
            st: ShellL {
                m: [z; 3],
                q: [z; 2],
                drill: z,
            },
            out: [[z; 6]; 3],
            out_d: [[z; 6]; 3],
        }
    }
}

/// Gather S::W triangles into `l` (every input and resultant).
#[inline(always)]
fn tri_gather<S: Lanes>(
    els: &[TriElem],
    nodes: Nodes<'_>,
    sts: &[ShellState],
    l: &mut TriLanes<S>,
) {
    let (els, sts) = (&els[..S::W], &sts[..S::W]);
    for i in 0..3 {
        l.input.x[i] = gather_v3(
            nodes.0,
            #[inline(always)]
            |k| els[k].nodes[i] as usize,
        );
        l.input.v[i] = gather_v3(
            nodes.1,
            #[inline(always)]
            |k| els[k].nodes[i] as usize,
        );
        l.input.w[i] = gather_v3(
            nodes.2,
            #[inline(always)]
            |k| els[k].nodes[i] as usize,
        );
        l.input.bx0[i] = gather(|k| els[k].bx0[i]);
        l.input.by0[i] = gather(|k| els[k].by0[i]);
    }
    l.input.area0 = gather(|k| els[k].area0);
    l.st = gather_shell(sts);
}

/// Resultants and force slots back; the Kelvin part into `damped` unless it is empty
/// (a body without Kelvin damping).
#[inline(always)]
fn tri_scatter<S: Lanes, const KELVIN: bool>(
    l: &TriLanes<S>,
    sts: &mut [ShellState],
    slots: &mut [Slot],
    damped: &mut [Slot],
    stream: bool,
) {
    scatter_shell(&l.st, &mut sts[..S::W]);
    if stream {
        S::stream_rows6(&l.out, slots);
    } else {
        for i in 0..3 {
            S::scatter_rows6(&l.out[i], slots, i, 3);
        }
    }
    if KELVIN {
        for i in 0..3 {
            S::scatter_rows6(&l.out_d[i], damped, i, 3);
        }
    }
}

#[inline(always)]
fn tri_compute<S: Lanes, const KELVIN: bool>(
    k: &Consts<S>,
    sec: &Section,
    e0: usize,
    h: S,
    l: &mut TriLanes<S>,
    sums: &mut ForceSums,
) -> Result<(), (usize, ElemFailure)> {
    let r = tri_kernel::<S, KELVIN>(k, &l.input, h, &mut l.st, &mut l.out, &mut l.out_d);
    book(sec, &r, S::splat(0.0), l.input.area0, e0, sums)
}

/// Triangles `els` (at least S::W of them; the first S::W) from element index `e0`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn tri_batch<S: Lanes, const KELVIN: bool>(
    k: &Consts<S>,
    sec: &Section,
    els: &[TriElem],
    e0: usize,
    nodes: Nodes<'_>,
    h: S,
    sts: &mut [ShellState],
    (slots, damped): (&mut [Slot], &mut [Slot]),
    sums: &mut ForceSums,
    buf: &mut TriLanes<S>,
    stream: bool,
) -> Result<(), (usize, ElemFailure)> {
    tri_gather(els, nodes, sts, buf);
    tri_compute::<S, KELVIN>(k, sec, e0, h, buf, sums)?;
    tri_scatter::<S, KELVIN>(buf, sts, slots, damped, stream);
    Ok(())
}

/// Lanes of a quad batch: kernel input, resultants, nodal forces and their Kelvin part.
#[derive(Debug, Clone, Copy)]
struct QuadLanes<S> {
    input: QuadIn<S>,
    st: ShellL<S>,
    hg: HgL<S>,
    out: [[S; 6]; 4],
    out_d: [[S; 6]; 4],
}

impl<S: Real> QuadLanes<S> {
    fn zero() -> Self {
        let z = S::splat(0.0);
        let z3 = V3::new(z, z, z);
        Self {
            input: QuadIn {
                x: [z3; 4],
                v: [z3; 4],
                w: [z3; 4],
                bx0: [z; 2],
                by0: [z; 2],
                gamma: [z; 4],
                area0: z,
                e0: [z; 3],
                k_m: z,
                k_w: z,
                k_th: z,
            },
            st: ShellL {
                m: [z; 3],
                q: [z; 2],
                drill: z,
            },
            hg: HgL { w: z, th: [z; 2] },
            out: [[z; 6]; 4],
            out_d: [[z; 6]; 4],
        }
    }
}

/// Gather S::W quads into `l` (every input and resultant).
#[inline(always)]
fn quad_gather<S: Lanes>(
    kc: &Consts<S>,
    els: &[QuadElem],
    nodes: Nodes<'_>,
    sts: &[ShellState],
    hgs: &[HourglassState],
    l: &mut QuadLanes<S>,
) {
    let (els, sts, hgs) = (&els[..S::W], &sts[..S::W], &hgs[..S::W]);
    let q = &mut l.input;
    for i in 0..4 {
        q.x[i] = gather_v3(
            nodes.0,
            #[inline(always)]
            |k| els[k].nodes[i] as usize,
        );
        q.v[i] = gather_v3(
            nodes.1,
            #[inline(always)]
            |k| els[k].nodes[i] as usize,
        );
        q.w[i] = gather_v3(
            nodes.2,
            #[inline(always)]
            |k| els[k].nodes[i] as usize,
        );
    }
    q.bx0 = [gather(|k| els[k].bx0[0]), gather(|k| els[k].bx0[1])];
    q.by0 = [gather(|k| els[k].by0[0]), gather(|k| els[k].by0[1])];
    q.e0 = [
        gather(|k| els[k].e0[0]),
        gather(|k| els[k].e0[1]),
        gather(|k| els[k].e0[2]),
    ];
    q.area0 = gather(|k| els[k].area0);
    // derived, not stored: fewer bytes per element (QuadElem)
    let (hx, hy) = (gather(|k| els[k].hx), gather(|k| els[k].hy));
    q.gamma = hourglass_shape(q.bx0, q.by0, hx, hy);
    [q.k_m, q.k_w, q.k_th] = hourglass_stiffness(kc, q.area0, gather(|k| els[k].bb));
    l.st = gather_shell(sts);
    l.hg = HgL {
        w: gather(|k| hgs[k].w),
        th: [gather(|k| hgs[k].th[0]), gather(|k| hgs[k].th[1])],
    };
}

/// Resultants and force slots back; the Kelvin part into `damped` unless it is empty.
#[inline(always)]
fn quad_scatter<S: Lanes, const KELVIN: bool>(
    l: &QuadLanes<S>,
    sts: &mut [ShellState],
    hgs: &mut [HourglassState],
    (slots, damped): (&mut [Slot], &mut [Slot]),
    stream: bool,
) {
    scatter_shell(&l.st, &mut sts[..S::W]);
    let (w, t0, t1) = (
        l.hg.w.to_array(),
        l.hg.th[0].to_array(),
        l.hg.th[1].to_array(),
    );
    for (k, h) in hgs[..S::W].iter_mut().enumerate() {
        h.w = w[k];
        h.th = [t0[k], t1[k]];
    }
    if stream {
        S::stream_rows6(&l.out, slots);
    } else {
        for i in 0..4 {
            S::scatter_rows6(&l.out[i], slots, i, 4);
        }
    }
    if KELVIN {
        for i in 0..4 {
            S::scatter_rows6(&l.out_d[i], damped, i, 4);
        }
    }
}

#[inline(always)]
fn quad_compute<S: Lanes, const KELVIN: bool>(
    k: &Consts<S>,
    sec: &Section,
    e0: usize,
    h: S,
    l: &mut QuadLanes<S>,
    sums: &mut ForceSums,
) -> Result<(), (usize, ElemFailure)> {
    let (r, extra) = quad_kernel::<S, KELVIN>(
        k,
        &l.input,
        h,
        &mut l.st,
        &mut l.hg,
        &mut l.out,
        &mut l.out_d,
    );
    let c = &extra.corners;
    let convex = c[0].all_above(0.0, true)
        && c[1].all_above(0.0, true)
        && c[2].all_above(0.0, true)
        && c[3].all_above(0.0, true);
    if !convex {
        let corners = extra.corners.map(|c| c.to_array());
        for ln in 0..S::W {
            for (corner, c) in corners.iter().enumerate() {
                if c[ln].is_nan() || c[ln] <= 0.0 {
                    return Err((e0 + ln, ElemFailure::Inverted { corner }));
                }
            }
        }
    }
    book(sec, &r, extra.hourglass, l.input.area0, e0, sums)
}

/// Quads `els` (at least S::W of them; the first S::W) from element index `e0`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn quad_batch<S: Lanes, const KELVIN: bool>(
    k: &Consts<S>,
    sec: &Section,
    els: &[QuadElem],
    e0: usize,
    nodes: Nodes<'_>,
    h: S,
    sts: &mut [ShellState],
    hgs: &mut [HourglassState],
    slots: (&mut [Slot], &mut [Slot]),
    sums: &mut ForceSums,
    buf: &mut QuadLanes<S>,
    stream: bool,
) -> Result<(), (usize, ElemFailure)> {
    quad_gather(k, els, nodes, sts, hgs, buf);
    quad_compute::<S, KELVIN>(k, sec, e0, h, buf, sums)?;
    quad_scatter::<S, KELVIN>(buf, sts, hgs, slots, stream);
    Ok(())
}

/// The slots of elements from index `j` on (`per` slots per element); an empty slice
/// stays empty (a body without Kelvin damping has no Kelvin slots).
#[inline(always)]
fn slots_from(slots: &mut [Slot], per: usize, j: usize) -> &mut [Slot] {
    slots.get_mut(per * j..).unwrap_or_default()
}

/// One chunk of triangles: forces into `slots` (3 per element), resultants updated.
#[derive(Debug)]
pub struct TriChunk<'a> {
    pub sec: &'a Section,
    pub stab: &'a Stabilization,
    pub els: &'a [TriElem],
    pub states: &'a mut [ShellState],
    pub slots: &'a mut [Slot],
    /// The Kelvin-damping part of the same forces (3 per element), for the energy
    /// ledger; empty for a material without Kelvin damping (nothing written).
    pub damped: &'a mut [Slot],
    pub nodes: Nodes<'a>,
    pub h: f64,
    /// Body-wide index of the chunk's first element.
    pub first: usize,
    /// `BodyDef::uncounted` (a part of a split body), else None.
    pub uncounted: &'a Option<std::sync::Arc<[bool]>>,
    /// Write the force slots with non-temporal stores (`forces::stream_slots`).
    pub stream: bool,
}

impl Lanewise for TriChunk<'_> {
    type Output = ChunkResult;

    #[inline(always)]
    fn run<S: Lanes>(self) -> ChunkResult {
        // two instances: an undamped body never sees the Kelvin slots' code
        if self.damped.is_empty() {
            self.run_with::<S, false>()
        } else {
            self.run_with::<S, true>()
        }
    }
}

impl TriChunk<'_> {
    #[inline(always)]
    fn run_with<S: Lanes, const KELVIN: bool>(self) -> ChunkResult {
        let (kw, k1) = (
            Consts::<S>::new(self.sec, self.stab),
            Consts::<f64>::new(self.sec, self.stab),
        );
        let (els, sts, slots, damped) = (self.els, self.states, self.slots, self.damped);
        let mut sums = ForceSums {
            uncounted: self.uncounted.clone(),
            ..ForceSums::default()
        };
        let (mut buf, mut buf1) = (TriLanes::<S>::zero(), TriLanes::<f64>::zero());
        let w = S::W;
        let full = els.len() - els.len() % w;
        let mut j = 0;
        while j < full {
            tri_batch::<_, KELVIN>(
                &kw,
                self.sec,
                &els[j..],
                self.first + j,
                self.nodes,
                S::splat(self.h),
                &mut sts[j..],
                (&mut slots[3 * j..], slots_from(damped, 3, j)),
                &mut sums,
                &mut buf,
                self.stream,
            )?;
            j += w;
        }
        while j < els.len() {
            tri_batch::<_, KELVIN>(
                &k1,
                self.sec,
                &els[j..],
                self.first + j,
                self.nodes,
                self.h,
                &mut sts[j..],
                (&mut slots[3 * j..], slots_from(damped, 3, j)),
                &mut sums,
                &mut buf1,
                false,
            )?;
            j += 1;
        }
        if self.stream {
            S::stream_fence();
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
    /// The Kelvin-damping part of the same forces (4 per element), for the energy
    /// ledger; empty for a material without Kelvin damping (nothing written).
    pub damped: &'a mut [Slot],
    pub nodes: Nodes<'a>,
    pub h: f64,
    /// Body-wide index of the chunk's first element.
    pub first: usize,
    /// `BodyDef::uncounted` (a part of a split body), else None.
    pub uncounted: &'a Option<std::sync::Arc<[bool]>>,
    /// Write the force slots with non-temporal stores (`forces::stream_slots`).
    pub stream: bool,
}

impl Lanewise for QuadChunk<'_> {
    type Output = ChunkResult;

    #[inline(always)]
    fn run<S: Lanes>(self) -> ChunkResult {
        if self.damped.is_empty() {
            self.run_with::<S, false>()
        } else {
            self.run_with::<S, true>()
        }
    }
}

impl QuadChunk<'_> {
    #[inline(always)]
    fn run_with<S: Lanes, const KELVIN: bool>(self) -> ChunkResult {
        let (kw, k1) = (
            Consts::<S>::new(self.sec, self.stab),
            Consts::<f64>::new(self.sec, self.stab),
        );
        let (els, sts, hgs) = (self.els, self.states, self.hourglass);
        let (slots, damped) = (self.slots, self.damped);
        let mut sums = ForceSums {
            uncounted: self.uncounted.clone(),
            ..ForceSums::default()
        };
        let (mut buf, mut buf1) = (QuadLanes::<S>::zero(), QuadLanes::<f64>::zero());
        let w = S::W;
        let full = els.len() - els.len() % w;
        let mut j = 0;
        while j < full {
            quad_batch::<_, KELVIN>(
                &kw,
                self.sec,
                &els[j..],
                self.first + j,
                self.nodes,
                S::splat(self.h),
                &mut sts[j..],
                &mut hgs[j..],
                (&mut slots[4 * j..], slots_from(damped, 4, j)),
                &mut sums,
                &mut buf,
                self.stream,
            )?;
            j += w;
        }
        while j < els.len() {
            quad_batch::<_, KELVIN>(
                &k1,
                self.sec,
                &els[j..],
                self.first + j,
                self.nodes,
                self.h,
                &mut sts[j..],
                &mut hgs[j..],
                (&mut slots[4 * j..], slots_from(damped, 4, j)),
                &mut sums,
                &mut buf1,
                false,
            )?;
            j += 1;
        }
        if self.stream {
            S::stream_fence();
        }
        Ok(sums)
    }
}
