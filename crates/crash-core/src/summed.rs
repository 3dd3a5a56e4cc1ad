//! Pipeline stage (element forces, one thread, large bodies): the element forces carried
//! to the node loop as per-node sums instead of per-element slots.
//!
//! The element stage normally writes every element's force slots (3 or 4 per element,
//! 48 bytes each) and the node loop gathers them per node in element order. When a
//! body's per-cycle data exceed the last-level cache (`forces::stream_slots`) that is a
//! round trip to memory of the whole slot array each cycle. On one thread the element
//! chunks can instead be computed in order into a small buffer and added at once into
//! a sum per node (`BodyState::node_sums`, 48 bytes per node, read in node order by the
//! node loop): every node's sum then takes the gather's additions in the gather's order
//! (+0.0, then its slots in element order), so a run gives the same bits either way.
//!
//! The slots are then not current. `Body::settle` (or `Body::settled_state` for a copy)
//! writes them, in a form every gather reads back exactly: each node's sum in its first
//! slot and -0.0 in every other. A sum that starts from +0.0 is never -0.0 and
//! x + (-0.0) = x for every x, so a gather of all the slots of a node, in any order,
//! gives the sum (a part of a split body gathers all the slots of its owned nodes).
//! Whatever takes a state out of its group (snapshots, migrations, checkpoints, a split
//! into parts) takes it settled.

use crate::body::{Body, BodyDef, BodyState};
use crate::element::batch::{ChunkResult, QuadChunk, TriChunk};
use crate::element::simd::dispatch;
use crate::element::Slot;
use crate::forces::{cycle_bytes, last_level_cache, CHUNK};
use std::borrow::Cow;
use std::sync::atomic::{AtomicU8, Ordering};

/// 0: by the rule (`wanted`); 1: never; 2: always for a whole body.
static MODE: AtomicU8 = AtomicU8::new(0);

/// Override the rule for whole bodies in this process: Some(true) always sums (on any
/// thread count), Some(false) never, None the rule. Results are the same bits either
/// way: tests and measurements use it. `CRASH_SUMMED=0|1` in the environment sets it
/// at the first use.
pub fn set_summed_slots(mode: Option<bool>) {
    MODE.store(
        match mode {
            None => 0,
            Some(false) => 1,
            Some(true) => 2,
        },
        Ordering::Relaxed,
    );
}

fn mode() -> u8 {
    static ENV: std::sync::Once = std::sync::Once::new();
    ENV.call_once(|| match std::env::var("CRASH_SUMMED").as_deref() {
        Ok("0") => set_summed_slots(Some(false)),
        Ok("1") => set_summed_slots(Some(true)),
        _ => {}
    });
    MODE.load(Ordering::Relaxed)
}

/// Whether `d`'s element stage carries its forces as node sums this cycle: a whole,
/// deformable body on one thread (the chunks must run in element order) whose
/// per-cycle data (`forces::cycle_bytes`) exceed a quarter of the last-level cache. A
/// part of a split body never does: its chunks are computed in two rounds (inner ones
/// while the halo travels).
///
/// The quarter is measured (docs/performance.md, session 35): where the slots stay in
/// the caches the scalar additions into the node sums cost up to 2 ns per element more
/// than the gather (5 000 triangles, 1.3 MB per cycle) or the same (28 800, 7.6 MB);
/// where the slots come from memory they save 8-14 ns (51 200 triangles, 13.5 MB, and
/// more).
pub(crate) fn wanted(d: &BodyDef) -> bool {
    let whole = !d.kinematic && d.halo_nodes == 0 && d.uncounted.is_none();
    whole
        && match mode() {
            1 => false,
            2 => true,
            _ => rayon::current_num_threads() == 1 && cycle_bytes(d) > last_level_cache() / 4,
        }
}

impl Body {
    /// Every element chunk in element order (triangles, then quads), each into a
    /// buffer and then added into its nodes' sums; the chunks' results in order.
    pub(crate) fn summed_chunks(&mut self, h: f64) -> Vec<Option<ChunkResult>> {
        self.fit_slots();
        let d = &*self.def;
        let (sec, stab) = (d.section, d.stab);
        let (nn, nt) = (d.x0.len(), d.tris.len());
        let damped = d.slot_count() > d.gather_slot.len();
        let st = &mut self.state;
        st.node_sums.clear();
        st.node_sums
            .resize(if damped { 2 * nn } else { nn }, [0.0; 6]);
        let (sums, kelvin) = st.node_sums.split_at_mut(nn);
        let nodes = (&st.x[..], &st.v[..], &st.w[..]);
        let mut buf = vec![[0.0; 6]; 4 * CHUNK];
        let mut kbuf = vec![[0.0; 6]; if damped { 4 * CHUNK } else { 0 }];
        let (tri_state, quad_state) = st.shell.split_at_mut(nt);
        let uncounted = &d.uncounted;
        let mut out = Vec::with_capacity(nt.div_ceil(CHUNK) + d.quads.len().div_ceil(CHUNK));
        let tris = d.tris.chunks(CHUNK).zip(tri_state.chunks_mut(CHUNK));
        for (ci, (els, states)) in tris.enumerate() {
            let n = 3 * els.len();
            let r = dispatch(TriChunk {
                sec: &sec,
                stab: &stab,
                els,
                states,
                slots: &mut buf[..n],
                damped: &mut kbuf[..if damped { n } else { 0 }],
                nodes,
                h,
                first: ci * CHUNK,
                uncounted,
                stream: false,
            });
            let corner = |k: usize| els[k / 3].nodes[k % 3] as usize;
            add_into(sums, &buf[..n], corner);
            if damped {
                add_into(kelvin, &kbuf[..n], corner);
            }
            out.push(Some(r));
        }
        let quads = d.quads.chunks(CHUNK).zip(quad_state.chunks_mut(CHUNK));
        for (ci, ((els, states), hourglass)) in
            quads.zip(st.hourglass.chunks_mut(CHUNK)).enumerate()
        {
            let n = 4 * els.len();
            let r = dispatch(QuadChunk {
                sec: &sec,
                stab: &stab,
                els,
                states,
                hourglass,
                slots: &mut buf[..n],
                damped: &mut kbuf[..if damped { n } else { 0 }],
                nodes,
                h,
                first: nt + ci * CHUNK,
                uncounted,
                stream: false,
            });
            let corner = |k: usize| els[k / 4].nodes[k % 4] as usize;
            add_into(sums, &buf[..n], corner);
            if damped {
                add_into(kelvin, &kbuf[..n], corner);
            }
            out.push(Some(r));
        }
        out
    }

    /// Write the slots from the node sums, if the forces are carried as node sums
    /// (module doc); the state is then of the usual form.
    pub fn settle(&mut self) {
        if let Cow::Owned(slots) = slots_of(&self.def, &self.state) {
            self.state.slots = slots;
        }
        self.state.node_sums.clear();
    }

    /// A copy of the state, settled: what leaves the group (snapshots, migrations,
    /// checkpoints).
    pub fn settled_state(&self) -> BodyState {
        match slots_of(&self.def, &self.state) {
            Cow::Borrowed(_) => self.state.clone(),
            Cow::Owned(slots) => {
                let s = &self.state;
                BodyState {
                    x: s.x.clone(),
                    v: s.v.clone(),
                    w: s.w.clone(),
                    shell: s.shell.clone(),
                    hourglass: s.hourglass.clone(),
                    slots,
                    node_sums: Vec::new(),
                    f_contact: s.f_contact.clone(),
                    energy: s.energy,
                    internal_now: s.internal_now,
                    hourglass_now: s.hourglass_now,
                }
            }
        }
    }
}

/// The force slots of state `s` of a body defined by `d`: its slots, or, where the
/// forces are carried as node sums, the slots written from them (module doc).
pub fn slots_of<'s>(d: &BodyDef, s: &'s BodyState) -> Cow<'s, [Slot]> {
    if s.node_sums.is_empty() {
        return Cow::Borrowed(&s.slots);
    }
    let (ns, nn) = (d.gather_slot.len(), d.x0.len());
    let mut slots = vec![[-0.0; 6]; s.slots.len()];
    for (half, sums) in s.node_sums.chunks(nn).enumerate() {
        for (i, sum) in sums.iter().enumerate() {
            let (a, b) = (d.gather_start[i] as usize, d.gather_start[i + 1] as usize);
            if a < b {
                slots[half * ns + d.gather_slot[a] as usize] = *sum;
            }
        }
    }
    Cow::Owned(slots)
}

/// Add the chunk's slots `buf` (slot k at node `corner(k)`) into the nodes' sums, in
/// element order.
#[inline(always)]
fn add_into(sums: &mut [Slot], buf: &[Slot], corner: impl Fn(usize) -> usize) {
    for (k, s) in buf.iter().enumerate() {
        let t = &mut sums[corner(k)];
        for c in 0..6 {
            t[c] += s[c];
        }
    }
}
