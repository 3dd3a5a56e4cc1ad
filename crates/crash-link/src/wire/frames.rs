//! A split body's frame shares (`crash_io::PartFrame`) on the wire, checked on the way
//! in: the arrays must agree with the node and element lists.

use super::{pack3, unpack3};
use crash_io::PartFrame;
use crash_proto::pb;
use crash_proto::ProtoError;

pub(super) fn part_frame_to_pb(p: &PartFrame) -> pb::PartFrame {
    pb::PartFrame {
        id: p.id,
        nodes: p.nodes.clone(),
        elements: p.elements.clone(),
        x: pack3(&p.x),
        v: pack3(&p.v),
        w: pack3(&p.w),
        f_contact: pack3(&p.f_contact),
        von_mises_top: p.von_mises_top.clone(),
        von_mises_bottom: p.von_mises_bottom.clone(),
        n: p.n.iter().flatten().copied().collect(),
        m: p.m.iter().flatten().copied().collect(),
    }
}

pub(super) fn part_frame_from_pb(p: &pb::PartFrame) -> Result<PartFrame, ProtoError> {
    let id = p.id;
    let triples =
        |d: &[f64]| -> Vec<[f64; 3]> { d.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect() };
    if !p.n.len().is_multiple_of(3) || !p.m.len().is_multiple_of(3) {
        return Err(ProtoError::Invalid(format!(
            "frame share of body {id}: element triples are not whole"
        )));
    }
    let f = PartFrame {
        id,
        nodes: p.nodes.clone(),
        elements: p.elements.clone(),
        x: unpack3(id, "x", &p.x)?,
        v: unpack3(id, "v", &p.v)?,
        w: unpack3(id, "w", &p.w)?,
        f_contact: unpack3(id, "f_contact", &p.f_contact)?,
        von_mises_top: p.von_mises_top.clone(),
        von_mises_bottom: p.von_mises_bottom.clone(),
        n: triples(&p.n),
        m: triples(&p.m),
    };
    if !f.consistent() {
        return Err(ProtoError::Invalid(format!(
            "frame share of body {id}: arrays do not match its nodes and elements"
        )));
    }
    Ok(f)
}
