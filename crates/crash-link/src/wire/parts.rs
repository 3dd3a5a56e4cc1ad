//! The wire form of groups split over workers: split specs, part states (their points
//! as one raw block, protocol v13), element steps and closing-speed figures, parts'
//! full states, and the frames holders exchange directly (protocol v18).

use super::split_sizes;
use crate::command::SplitSpec;
use crash_core::contact::sweep::Momentum;
use crash_core::partition::{PairSpeed, PartDt, PartState, SplitFigures};
use crash_core::BodyState;
use crash_core::Vec3;
use crash_proto::pb;
use crash_proto::{state_from_pb, state_to_pb, ProtoError};

pub(super) fn spec_to_pb(s: &SplitSpec) -> pb::SplitSpec {
    pb::SplitSpec {
        ids: s.ids.clone(),
        parts: s.parts.clone(),
        holder: s.holder.iter().flatten().copied().collect(),
        slot: s.slot,
        workers: s.workers.clone(),
        peers: s.peers.clone(),
    }
}

pub(super) fn spec_from_pb(s: Option<&pb::SplitSpec>) -> Result<SplitSpec, ProtoError> {
    let s = s.ok_or(ProtoError::Missing("share.spec"))?;
    if s.ids.len() != s.parts.len() {
        return Err(ProtoError::Invalid(
            "split: ids and part counts differ in length".into(),
        ));
    }
    if s.workers.len() != s.peers.len() {
        return Err(ProtoError::Invalid(
            "split: workers and peer addresses differ in length".into(),
        ));
    }
    Ok(SplitSpec {
        ids: s.ids.clone(),
        parts: s.parts.clone(),
        holder: split_sizes(&s.holder, &s.parts, "part holders")?,
        slot: s.slot,
        workers: s.workers.clone(),
        peers: s.peers.clone(),
    })
}

pub(super) fn part_states_to_pb(parts: &[PartState]) -> pb::PartStates {
    pb::PartStates {
        parts: parts
            .iter()
            .map(|p| pb::PartState {
                id: p.id,
                part: p.part,
                xvw: raw3(&[&p.x, &p.v, &p.w]),
                nx: p.x.len() as u32,
                nv: p.v.len() as u32,
                nw: p.w.len() as u32,
                max_move: p.max_move,
                max_move_node: p.max_move_node,
                bounds: vec![p.lo.x, p.lo.y, p.lo.z, p.hi.x, p.hi.y, p.hi.z],
                far: p.far,
                momentum: p.momentum.0.to_vec(),
            })
            .collect(),
    }
}

/// Points as raw little-endian doubles, one list after the other (x, y, z each).
pub(super) fn raw3(lists: &[&[Vec3]]) -> Vec<u8> {
    let n: usize = lists.iter().map(|l| l.len()).sum();
    // sized once and written in place: no capacity check per value
    let mut out = vec![0u8; 24 * n];
    let points = lists.iter().flat_map(|l| l.iter());
    for (c, p) in out.chunks_exact_mut(24).zip(points) {
        c[0..8].copy_from_slice(&p.x.to_le_bytes());
        c[8..16].copy_from_slice(&p.y.to_le_bytes());
        c[16..24].copy_from_slice(&p.z.to_le_bytes());
    }
    out
}

/// The three point lists of `raw3`, of the stated lengths; the block must hold exactly
/// that many points (checked before anything is allocated).
pub(super) fn unraw3(
    id: u32,
    part: u32,
    d: &[u8],
    n: [u32; 3],
) -> Result<[Vec<Vec3>; 3], ProtoError> {
    let want = n.iter().map(|&k| 24 * k as u64).sum::<u64>();
    if d.len() as u64 != want {
        return Err(ProtoError::Invalid(format!(
            "part {part} of body {id}: {} bytes of points, {want} stated",
            d.len()
        )));
    }
    let f = |b: &[u8]| f64::from_le_bytes(b.try_into().unwrap_or([0; 8]));
    let mut points = d
        .chunks_exact(24)
        .map(|c| Vec3::new(f(&c[0..8]), f(&c[8..16]), f(&c[16..24])));
    Ok(n.map(|k| points.by_ref().take(k as usize).collect()))
}

pub(super) fn part_states_from_pb(
    p: Option<&pb::PartStates>,
) -> Result<Vec<PartState>, ProtoError> {
    let Some(p) = p else {
        return Ok(Vec::new());
    };
    p.parts
        .iter()
        .map(|s| {
            let [x, v, w] = unraw3(s.id, s.part, &s.xvw, [s.nx, s.nv, s.nw])?;
            let [lx, ly, lz, hx, hy, hz] = s.bounds[..] else {
                return Err(ProtoError::Invalid(format!(
                    "part {} of body {}: a box is 6 numbers",
                    s.part, s.id
                )));
            };
            let [px, py, pz] = s.momentum[..] else {
                return Err(ProtoError::Invalid(format!(
                    "part {} of body {}: a momentum is 3 integers",
                    s.part, s.id
                )));
            };
            Ok(PartState {
                id: s.id,
                part: s.part,
                x,
                v,
                w,
                lo: Vec3::new(lx, ly, lz),
                hi: Vec3::new(hx, hy, hz),
                far: s.far,
                max_move: s.max_move,
                max_move_node: s.max_move_node,
                momentum: Momentum([px, py, pz]),
            })
        })
        .collect()
}

pub(super) fn part_dts_to_pb(f: &SplitFigures) -> pb::PartDts {
    let (d, p) = (&f.dts, &f.pairs);
    pb::PartDts {
        id: d.iter().map(|d| d.id).collect(),
        dt: d.iter().map(|d| d.dt).collect(),
        element: d.iter().map(|d| d.element).collect(),
        pair_a: p.iter().map(|p| p.a).collect(),
        pair_b: p.iter().map(|p| p.b).collect(),
        pair_c: p.iter().map(|p| p.c).collect(),
        pair_max: p.iter().flat_map(|p| p.max).collect(),
    }
}

pub(super) fn part_dts_from_pb(d: &pb::PartDts) -> Result<SplitFigures, ProtoError> {
    if d.dt.len() != d.id.len() || d.element.len() != d.id.len() {
        return Err(ProtoError::Invalid(
            "part steps: columns differ in length".into(),
        ));
    }
    let n = d.pair_a.len();
    if d.pair_b.len() != n || d.pair_c.len() != n || d.pair_max.len() != 4 * n {
        return Err(ProtoError::Invalid(
            "closing-speed figures: columns differ in length (4 maxima a pair)".into(),
        ));
    }
    Ok(SplitFigures {
        dts: d
            .id
            .iter()
            .zip(&d.dt)
            .zip(&d.element)
            .map(|((&id, &dt), &element)| PartDt { id, dt, element })
            .collect(),
        pairs: (0..n)
            .map(|k| PairSpeed {
                a: d.pair_a[k],
                b: d.pair_b[k],
                c: d.pair_c[k],
                max: std::array::from_fn(|j| d.pair_max[4 * k + j]),
            })
            .collect(),
    })
}

pub(super) fn part_bodies_to_pb(parts: &[(u32, u32, BodyState)]) -> pb::PartBodyStates {
    pb::PartBodyStates {
        part: parts.iter().map(|p| p.1).collect(),
        states: parts.iter().map(|(id, _, s)| state_to_pb(*id, s)).collect(),
    }
}

pub(super) fn part_bodies_from_pb(
    p: &pb::PartBodyStates,
) -> Result<Vec<(u32, u32, BodyState)>, ProtoError> {
    if p.part.len() != p.states.len() {
        return Err(ProtoError::Invalid(
            "part states: part column and states differ in length".into(),
        ));
    }
    p.part
        .iter()
        .zip(&p.states)
        .map(|(&q, s)| Ok((s.id, q, state_from_pb(s)?)))
        .collect()
}

/// One frame between two holders (`PeerHalo`): the sender's part states for the
/// receiver at step `step`, or None: the sender stopped (a fault or an error).
pub fn peer_halo_to_pb(step: u64, parts: Option<&[PartState]>) -> pb::PeerHalo {
    pb::PeerHalo {
        step,
        abort: parts.is_none(),
        parts: parts.map(part_states_to_pb),
    }
}

/// A `PeerHalo` frame: its step and its part states (None: the sender stopped).
pub fn peer_halo_from_pb(p: &pb::PeerHalo) -> Result<(u64, Option<Vec<PartState>>), ProtoError> {
    if p.abort {
        return Ok((p.step, None));
    }
    Ok((p.step, Some(part_states_from_pb(p.parts.as_ref())?)))
}
