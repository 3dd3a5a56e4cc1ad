//! A part's share of a split body's frame (`crash_core::partition`): what the part
//! alone knows, its owned nodes and the elements it holds, by their indices in the
//! whole body. The holders of a split group each send theirs and the master scatters
//! them into the body's frame (`FrameFromParts`), so a frame of a split group
//! needs no assembly of whole bodies on one worker and is computed by every holder
//! at once.
//!
//! Same bits as the whole body's frame: every node is owned by one part and an owned
//! node's x, v, w and contact force are the whole body's; an element's bending moments
//! are its state, the same in every part that holds it, and its membrane forces and
//! stresses are computed from its own nodes (owned or halo, the whole body's positions
//! after the step's exchange) by the same code (`FrameBody::complete`).

use crate::frame::FrameBody;
use crash_core::{Body, Vec3};

/// A part's share of a split body's frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PartFrame {
    /// The whole body's id.
    pub id: u32,
    /// Whole-body index of each owned node (the order of the nodal arrays).
    pub nodes: Vec<u32>,
    /// Whole-body index of each element held (the order of the element arrays).
    pub elements: Vec<u32>,
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    pub w: Vec<Vec3>,
    pub f_contact: Vec<Vec3>,
    pub von_mises_top: Vec<f64>,
    pub von_mises_bottom: Vec<f64>,
    pub n: Vec<[f64; 3]>,
    pub m: Vec<[f64; 3]>,
}

impl PartFrame {
    /// The share of a part whose body holds `owned` owned nodes first, `node` and
    /// `element` mapping its local nodes and elements to the whole body's.
    pub fn capture(id: u32, body: &Body, owned: usize, node: &[u32], element: &[u32]) -> Self {
        let f = FrameBody::capture(body);
        let own = |a: &[Vec3]| a[..owned.min(a.len())].to_vec();
        Self {
            id,
            nodes: node[..owned.min(node.len())].to_vec(),
            elements: element.to_vec(),
            x: own(&f.x),
            v: own(&f.v),
            w: own(&f.w),
            f_contact: own(&f.f_contact),
            von_mises_top: f.von_mises_top,
            von_mises_bottom: f.von_mises_bottom,
            n: f.n,
            m: f.m,
        }
    }

    /// Whether the arrays agree with the index lists.
    pub fn consistent(&self) -> bool {
        let (nn, ne) = (self.nodes.len(), self.elements.len());
        [&self.x, &self.v, &self.w, &self.f_contact]
            .iter()
            .all(|a| a.len() == nn)
            && self.von_mises_top.len() == ne
            && self.von_mises_bottom.len() == ne
            && self.n.len() == ne
            && self.m.len() == ne
    }
}

/// A split body's frame filled from its parts' shares: a frame of the whole body (its
/// arrays sized for it, e.g. as it was when split) whose every node and element a share
/// must cover before it is `finish`ed, so no stale value can stand in a frame.
#[derive(Debug, Clone)]
pub struct FrameFromParts {
    frame: FrameBody,
    nodes: Vec<bool>,
    elements: Vec<bool>,
}

impl FrameFromParts {
    /// Start from `frame`, a frame of the whole body (every array it will overwrite).
    pub fn new(frame: FrameBody) -> Self {
        let (nn, ne) = (frame.x.len(), frame.von_mises_top.len());
        Self {
            frame,
            nodes: vec![false; nn],
            elements: vec![false; ne],
        }
    }

    /// Scatter a part's share in: its owned nodes and its elements. Errors name what
    /// does not fit (another body, an index out of range, arrays that disagree with the
    /// indices or a frame that is not whole).
    pub fn fill(&mut self, p: &PartFrame) -> Result<(), String> {
        let f = &mut self.frame;
        if p.id != f.id {
            return Err(format!(
                "a share of body {} in the frame of body {}",
                p.id, f.id
            ));
        }
        if !p.consistent() {
            return Err("a part's arrays do not match its nodes and elements".into());
        }
        let (nn, ne) = (self.nodes.len(), self.elements.len());
        if [&f.v, &f.w, &f.f_contact].iter().any(|a| a.len() != nn)
            || [f.von_mises_bottom.len(), f.n.len(), f.m.len()]
                .iter()
                .any(|&l| l != ne)
        {
            return Err("the body's frame is not whole".into());
        }
        if p.nodes.iter().any(|&k| k as usize >= nn) || p.elements.iter().any(|&e| e as usize >= ne)
        {
            return Err("a part names a node or an element out of range".into());
        }
        for (k, &i) in p.nodes.iter().enumerate() {
            let i = i as usize;
            f.x[i] = p.x[k];
            f.v[i] = p.v[k];
            f.w[i] = p.w[k];
            f.f_contact[i] = p.f_contact[k];
            self.nodes[i] = true;
        }
        for (k, &e) in p.elements.iter().enumerate() {
            let e = e as usize;
            f.von_mises_top[e] = p.von_mises_top[k];
            f.von_mises_bottom[e] = p.von_mises_bottom[k];
            f.n[e] = p.n[k];
            f.m[e] = p.m[k];
            self.elements[e] = true;
        }
        Ok(())
    }

    /// The body's frame, once the shares covered every node and every element.
    pub fn finish(self) -> Result<FrameBody, String> {
        if self.nodes.iter().all(|&c| c) && self.elements.iter().all(|&c| c) {
            Ok(self.frame)
        } else {
            Err(format!(
                "the frame shares of body {} leave nodes or elements out",
                self.frame.id
            ))
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // a test panics on failure
mod tests {
    use super::*;
    use crash_core::partition::{Partition, Split};
    use crash_core::shapes::{plate, ElementKind};
    use crash_core::{Material, Section, Stabilization};

    /// A plate of triangles and one of quads, deformed and moving, split in three by
    /// element bands: the parts' shares scattered into a stale frame of the whole give
    /// the whole body's frame bit for bit.
    #[test]
    fn part_shares_scattered_give_the_whole_bodys_frame_bit_for_bit() {
        for kind in [ElementKind::Tri, ElementKind::Quad] {
            let mesh = plate(0.2, 0.1, 6, 3, kind);
            let section = Section::new(Material::steel(), 1e-3);
            let mut b = Body::new(7, "p", &mesh, section, Stabilization::default()).unwrap();
            let ne = b.def.element_count();
            for (k, (x, v)) in b.state.x.iter_mut().zip(b.state.v.iter_mut()).enumerate() {
                let s = k as f64;
                x.z += 1e-4 * (0.7 * s).sin();
                *v = Vec3::new(0.1 * s, -0.2, (0.3 * s).cos());
            }
            for (k, e) in b.state.shell.iter_mut().enumerate() {
                e.m = [k as f64, -2.0 * k as f64, 0.5];
            }
            b.state.f_contact = (0..b.state.x.len())
                .map(|k| Vec3::new(0.0, 0.0, k as f64))
                .collect();
            let whole = FrameBody::capture(&b);
            let part_of: Vec<u32> = (0..ne as u32).map(|e| e * 3 / ne as u32).collect();
            let split = Split::new(&b, &Partition { parts: 3, part_of }).unwrap();
            // a frame of the whole body at another state: every array must be overwritten
            let mut stale = b.clone();
            for ((x, v), w) in stale
                .state
                .x
                .iter_mut()
                .zip(&mut stale.state.v)
                .zip(&mut stale.state.w)
            {
                x.z += 1.0;
                *v = -*v;
                *w = Vec3::new(1.0, 2.0, 3.0);
            }
            for e in &mut stale.state.shell {
                e.m = [9.0; 3];
            }
            stale.state.f_contact.clear();
            let mut f = FrameFromParts::new(FrameBody::capture(&stale));
            let mut short = f.clone();
            for p in &split.parts {
                let mut pb = p.body.clone();
                // what the part's pass left in its contact forces: the owned nodes'
                pb.state.f_contact = p
                    .node
                    .iter()
                    .map(|&g| b.state.f_contact[g as usize])
                    .collect();
                let share = PartFrame::capture(7, &pb, p.owned, &p.node, &p.element);
                f.fill(&share).unwrap();
                if p.node[0] != 0 {
                    short.fill(&share).unwrap();
                }
            }
            assert_eq!(f.finish().unwrap(), whole, "{kind:?}");
            // without the part owning node 0 the frame is refused
            assert!(short.finish().is_err(), "{kind:?}");
        }
    }

    #[test]
    fn a_share_out_of_range_is_refused() {
        let mut f = FrameFromParts::new(FrameBody {
            id: 1,
            x: vec![Vec3::zeros(); 2],
            v: vec![Vec3::zeros(); 2],
            w: vec![Vec3::zeros(); 2],
            f_contact: vec![Vec3::zeros(); 2],
            ..FrameBody::default()
        });
        let p = PartFrame {
            id: 1,
            nodes: vec![2],
            x: vec![Vec3::zeros()],
            v: vec![Vec3::zeros()],
            w: vec![Vec3::zeros()],
            f_contact: vec![Vec3::zeros()],
            ..PartFrame::default()
        };
        assert!(f.fill(&p).is_err());
        let q = PartFrame {
            nodes: vec![1],
            ..p.clone()
        };
        assert!(f.fill(&q).is_ok());
        assert!(f.fill(&PartFrame { id: 2, ..q }).is_err());
    }
}
