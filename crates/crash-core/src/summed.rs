//! Pipeline stage (element forces, one thread, large bodies): the element forces carried
//! to the node loop as per-node sums in the force slots themselves.
//!
//! The element stage normally writes every element's force slots (3 or 4 per element,
//! 48 bytes each) and the node loop gathers them per node in element order. When a
//! body's per-cycle data exceed the last-level cache (`forces::stream_slots`) that is a
//! round trip to memory of the whole slot array each cycle. On one thread the element
//! chunks can instead be computed in order into a small buffer and added at once into
//! one slot per node, the node's first in gather order: every node's sum then takes the
//! same additions in the same order as the gather (+0.0, then its slots in element
//! order), so the node loop reads the same bits from one slot per node.
//!
//! Every other slot holds -0.0. A sum that starts from +0.0 is never -0.0, and
//! x + (-0.0) = x for every x, so a gather of all the slots of a node, in any order,
//! also gives the sum: the state stays a valid state of the usual form wherever it goes
//! (snapshots, migrations, checkpoints, a split into parts, each of which gathers all
//! the slots of its owned nodes). `BodyState::slots_summed` marks the form; a state
//! without the mark (rebuilt elsewhere) is gathered slot by slot.

use crate::body::{Body, BodyDef};
use crate::element::batch::{ChunkResult, QuadChunk, TriChunk};
use crate::element::simd::dispatch;
use crate::element::Slot;
use crate::forces::{cycle_bytes, stream_slots, CHUNK};
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
/// deformable body whose per-cycle data exceed the last-level cache, on one thread (the
/// chunks must run in element order). A part of a split body never does: its chunks
/// are computed in two rounds (inner ones while the halo travels).
pub(crate) fn wanted(d: &BodyDef) -> bool {
    let whole = !d.kinematic && d.halo_nodes == 0 && d.uncounted.is_none();
    whole
        && match mode() {
            1 => false,
            2 => true,
            _ => rayon::current_num_threads() == 1 && stream_slots(cycle_bytes(d)),
        }
}

impl Body {
    /// Every element chunk in element order (triangles, then quads), each into a
    /// buffer and then added into its nodes' first slots; the chunks' results in order.
    pub(crate) fn summed_chunks(&mut self, h: f64) -> Vec<Option<ChunkResult>> {
        let d = &*self.def;
        let (sec, stab) = (d.section, d.stab);
        let nt = d.tris.len();
        let ns = d.gather_slot.len();
        let want = d.slot_count();
        let st = &mut self.state;
        if st.slots.len() < want {
            st.slots.resize(want, [0.0; 6]);
        }
        if !st.slots_summed {
            // slots of the usual form: -0.0 everywhere first (each node's first slot
            // is written whole below)
            st.slots.fill([-0.0; 6]);
        }
        let nodes = (&st.x[..], &st.v[..], &st.w[..]);
        let (slots, kelvin) = st.slots.split_at_mut(ns);
        let kelvin = &mut kelvin[..want - ns];
        let damped = !kelvin.is_empty();
        let mut buf = vec![[0.0; 6]; 4 * CHUNK];
        let mut kbuf = vec![[0.0; 6]; if damped { 4 * CHUNK } else { 0 }];
        let (tri_state, quad_state) = st.shell.split_at_mut(nt);
        let uncounted = &d.uncounted;
        let mut out = Vec::with_capacity(nt.div_ceil(CHUNK) + d.quads.len().div_ceil(CHUNK));
        for (ci, (els, states)) in d
            .tris
            .chunks(CHUNK)
            .zip(tri_state.chunks_mut(CHUNK))
            .enumerate()
        {
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
            let at = 3 * ci * CHUNK;
            let corner = |k: usize| els[k / 3].nodes[k % 3];
            add_into(d, slots, &buf[..n], at, corner);
            if damped {
                add_into(d, kelvin, &kbuf[..n], at, corner);
            }
            out.push(Some(r));
        }
        let quad_slots = 3 * nt;
        let chunks = d.quads.chunks(CHUNK).zip(quad_state.chunks_mut(CHUNK));
        for (ci, ((els, states), hourglass)) in
            chunks.zip(st.hourglass.chunks_mut(CHUNK)).enumerate()
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
            let at = quad_slots + 4 * ci * CHUNK;
            let corner = |k: usize| els[k / 4].nodes[k % 4];
            add_into(d, slots, &buf[..n], at, corner);
            if damped {
                add_into(d, kelvin, &kbuf[..n], at, corner);
            }
            out.push(Some(r));
        }
        st.slots_summed = true;
        out
    }
}

/// Add the chunk's slots `buf` (slot `at + k` of the body is `buf[k]`, at node
/// `corner(k)`) into their nodes' first slots. The first slot of a node is its lowest
/// slot: the element that owns it comes first in element order, so the node's sum
/// starts there, from +0.0, as the gather's does.
#[inline(always)]
fn add_into(
    d: &BodyDef,
    slots: &mut [Slot],
    buf: &[Slot],
    at: usize,
    corner: impl Fn(usize) -> u32,
) {
    let (gs, gi) = (&d.gather_start, &d.gather_slot);
    for (k, s) in buf.iter().enumerate() {
        let first = gi[gs[corner(k) as usize] as usize] as usize;
        let t = &mut slots[first];
        if first == at + k {
            *t = [0.0; 6];
        }
        for c in 0..6 {
            t[c] += s[c];
        }
    }
}
