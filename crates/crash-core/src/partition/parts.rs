//! One body split into parts that step like the whole, bit for bit.
//!
//! A node is owned by the part of its lowest-index element. A part holds its owned
//! nodes (first, in global order), then its halo nodes (the other nodes of its
//! elements, in global order), and every element that touches an owned node, in the
//! body's element order. Each owned node thus has all of its element contributions
//! locally and gathers them in the same order as the whole body: its force, and so its
//! update, has the same bits. Halo nodes are not integrated (`BodyDef::halo_nodes`):
//! after every update the driver copies their x, v, w (all the element kernels read of
//! a node) from their owners (`Split::exchange`), which is what would cross the wire.

use super::report::{element_in_whole, node_in_whole};
use super::Partition;
use crate::body::{Body, BodyState};
use crate::clock::Clock;
use crate::error::{CoreError, Fault};
use crate::integrate::NodeSums;
use crate::mesh::Mesh;
use crate::Vec3;
use std::sync::Arc;

/// One part of a split body.
#[derive(Debug, Clone)]
pub struct Part {
    /// The sub-body: nodes `0..owned` owned here, the rest halo.
    pub body: Body,
    pub owned: usize,
    /// Local node -> node of the whole body.
    pub node: Vec<u32>,
    /// Local element -> element of the whole body (triangles then quads in both).
    pub element: Vec<u32>,
    /// For each halo node (local index owned + j): its owner part and its local index
    /// there.
    pub halo_from: Vec<(u32, u32)>,
}

/// A body split into parts, with the maps to put it back together.
#[derive(Debug, Clone)]
pub struct Split {
    pub parts: Vec<Part>,
    /// Node of the whole body -> (owner part, local index in the owner).
    pub owner: Vec<(u32, u32)>,
}

impl Split {
    /// Split `whole` (definition and current state) by the element partition `p`.
    /// Definitions are copied, not recomputed (masses, inertias and element reference
    /// data keep their bits); the state is the whole body's at its nodes and elements.
    pub fn new(whole: &Body, p: &Partition) -> Result<Self, CoreError> {
        let d = &*whole.def;
        let (nn, ne) = (d.node_count(), d.element_count());
        let err = |what: String| CoreError::Other {
            body: d.name.clone(),
            what,
        };
        if p.part_of.len() != ne || p.part_of.iter().any(|&q| q as usize >= p.parts) {
            return Err(err(format!(
                "a partition of {} elements into {} parts does not fit a body of {ne} elements",
                p.part_of.len(),
                p.parts
            )));
        }
        let nodes_of = |e: usize| d.element_nodes(e);
        let owner_part = p.owners(d);
        if let Some(n) = owner_part.iter().position(|&q| q == u32::MAX) {
            return Err(err(format!("node {n} belongs to no element")));
        }
        let mut owner = vec![(0u32, 0u32); nn];
        let mut parts = Vec::with_capacity(p.parts);
        for q in 0..p.parts as u32 {
            let owned: Vec<u32> = (0..nn as u32)
                .filter(|&n| owner_part[n as usize] == q)
                .collect();
            if owned.is_empty() {
                return Err(err(format!("part {q} owns no node")));
            }
            let element: Vec<u32> = (0..ne as u32)
                .filter(|&e| {
                    nodes_of(e as usize)
                        .iter()
                        .any(|&n| owner_part[n as usize] == q)
                })
                .collect();
            let mut halo: Vec<u32> = element
                .iter()
                .flat_map(|&e| nodes_of(e as usize).iter().copied())
                .filter(|&n| owner_part[n as usize] != q)
                .collect();
            halo.sort_unstable();
            halo.dedup();
            for (i, &n) in owned.iter().enumerate() {
                owner[n as usize] = (q, i as u32);
            }
            let node: Vec<u32> = owned.iter().chain(&halo).copied().collect();
            // an element's energies are counted by the part owning its first node (a
            // part that holds it), so that the parts' energies add up to the whole's
            let uncounted: std::sync::Arc<[bool]> = element
                .iter()
                .map(|&e| owner_part[nodes_of(e as usize)[0] as usize] != q)
                .collect();
            parts.push((owned.len(), node, element, uncounted));
        }
        let parts = parts
            .into_iter()
            .map(|(n_owned, node, element, uncounted)| {
                let halo_from = node[n_owned..].iter().map(|&n| owner[n as usize]).collect();
                let mut body = sub_body(whole, &node, &element, n_owned)?;
                body.def_mut().uncounted = Some(uncounted);
                Ok(Part {
                    body,
                    owned: n_owned,
                    node,
                    element,
                    halo_from,
                })
            })
            .collect::<Result<Vec<_>, CoreError>>()?;
        Ok(Self { parts, owner })
    }

    /// Copy every halo node's x, v, w from its owner (after the owners' update, before
    /// the element forces).
    pub fn exchange(&mut self) {
        for q in 0..self.parts.len() {
            self.exchange_into(q);
        }
    }

    /// Copy the halo nodes' x, v, w of part q from their owners (halo slots are written,
    /// owned slots read: the order of the parts does not matter).
    pub fn exchange_into(&mut self, q: usize) {
        let incoming: Vec<(Vec3, Vec3, Vec3)> = self.parts[q]
            .halo_from
            .iter()
            .map(|&(o, i)| {
                let s = &self.parts[o as usize].body.state;
                let i = i as usize;
                (s.x[i], s.v[i], s.w[i])
            })
            .collect();
        let p = &mut self.parts[q];
        let (o, s) = (p.owned, &mut p.body.state);
        for (j, (x, v, w)) in incoming.into_iter().enumerate() {
            (s.x[o + j], s.v[o + j], s.w[o + j]) = (x, v, w);
        }
    }

    /// Start like `Group::start`: constraints at t = 0 and forces at the initial
    /// configuration. Returns the smallest element critical step over the parts (no
    /// safety factor), which is the whole body's: every element is in some part.
    pub fn start(&mut self) -> Result<f64, Fault> {
        for p in &mut self.parts {
            p.body.apply_constraints(0.0);
        }
        self.exchange();
        self.forces(0.0, 0)
    }

    /// Update the owned nodes of every part over the step of length `h` from `clock`.
    pub fn integrate(
        &mut self,
        clock: &Clock,
        h: f64,
        gravity: Vec3,
    ) -> Result<Vec<NodeSums>, Fault> {
        let sc = clock.step_of(h);
        // every part, then the fault one process would name (`Fault::order`)
        let mut fault = None;
        let mut sums = Vec::with_capacity(self.parts.len());
        for p in &mut self.parts {
            match p.body.integrate(&sc, gravity) {
                Ok(s) => sums.push(s),
                Err(f) => fault = Some(Fault::first_of(fault, node_in_whole(f, &p.node))),
            }
        }
        fault.map_or(Ok(sums), Err)
    }

    /// Element forces of every part (the step that led here: h, step); returns the
    /// smallest element critical step.
    pub fn forces(&mut self, h: f64, step: u64) -> Result<f64, Fault> {
        let mut dt = f64::INFINITY;
        let mut fault = None;
        for p in &mut self.parts {
            match p.body.internal_forces(h, step) {
                Ok(f) => dt = dt.min(f.dt),
                Err(f) => fault = Some(Fault::first_of(fault, element_in_whole(f, &p.element))),
            }
        }
        fault.map_or(Ok(dt), Err)
    }

    /// One step of length h from `clock`: integrate, exchange the halos, element forces
    /// at the new positions (the pipeline of `Group::advance` without contact). Returns
    /// the smallest element critical step of the new configuration.
    pub fn advance(&mut self, clock: &Clock, h: f64, gravity: Vec3) -> Result<f64, Fault> {
        self.integrate(clock, h, gravity)?;
        self.exchange();
        self.forces(h, clock.after(h).step)
    }

    /// Write the owned nodes' x, v, w of every part into `whole` (the body split).
    pub fn gather_into(&self, whole: &mut Body) {
        let s = &mut whole.state;
        for p in &self.parts {
            let ps = &p.body.state;
            for (i, &n) in p.node[..p.owned].iter().enumerate() {
                let n = n as usize;
                (s.x[n], s.v[n], s.w[n]) = (ps.x[i], ps.v[i], ps.w[i]);
            }
        }
    }

    /// Owned and halo node counts summed over the parts.
    pub fn node_counts(&self) -> (usize, usize) {
        self.parts.iter().fold((0, 0), |(o, h), p| {
            (o + p.owned, h + p.node.len() - p.owned)
        })
    }
}

/// The sub-body of the nodes `node` (owned first, the last `node.len() - owned` halo)
/// and the elements `element` of `whole`.
pub(super) fn sub_body(
    whole: &Body,
    node: &[u32],
    element: &[u32],
    owned: usize,
) -> Result<Body, CoreError> {
    let (d, s) = (&*whole.def, &whole.state);
    let nt = d.tris.len();
    let mut local = vec![u32::MAX; d.node_count()];
    for (i, &n) in node.iter().enumerate() {
        local[n as usize] = i as u32;
    }
    let map = |nodes: &[u32]| -> Vec<u32> { nodes.iter().map(|&n| local[n as usize]).collect() };
    let split = element.partition_point(|&e| (e as usize) < nt);
    let (tris, quads) = element.split_at(split);
    let mesh = Mesh {
        nodes: node.iter().map(|&n| d.x0[n as usize]).collect(),
        tris: tris
            .iter()
            .map(|&e| {
                let m = map(&d.tris[e as usize].nodes);
                [m[0], m[1], m[2]]
            })
            .collect(),
        quads: quads
            .iter()
            .map(|&e| {
                let m = map(&d.quads[e as usize - nt].nodes);
                [m[0], m[1], m[2], m[3]]
            })
            .collect(),
    };
    // the gather map and slot layout come from Body::new; everything with bits of its
    // own is copied from the whole body
    let mut b = Body::new(d.id, &d.name, &mesh, d.section, d.stab)?;
    let pd = b.def_mut();
    for (pe, &e) in pd.tris.iter_mut().zip(tris) {
        let nodes = pe.nodes;
        *pe = d.tris[e as usize];
        pe.nodes = nodes;
    }
    for (pe, &e) in pd.quads.iter_mut().zip(quads) {
        let nodes = pe.nodes;
        *pe = d.quads[e as usize - nt];
        pe.nodes = nodes;
    }
    let pick = |v: &[f64]| -> Vec<f64> { node.iter().map(|&n| v[n as usize]).collect() };
    pd.mass = pick(&d.mass);
    pd.inertia = pick(&d.inertia);
    pd.fixed = node.iter().map(|&n| d.fixed[n as usize]).collect();
    pd.program = node.iter().map(|&n| d.program[n as usize]).collect();
    pd.programs = d.programs.clone();
    pd.curves = d.curves.clone();
    pd.mass_damping = d.mass_damping;
    // loads of the owned nodes, in the whole body's order (sorted by node, stable)
    pd.loads = d
        .loads
        .iter()
        .filter(|l| (local[l.node as usize] as usize) < owned)
        .map(|l| {
            let mut l = *l;
            l.node = local[l.node as usize];
            l
        })
        .collect();
    pd.loads.sort_by_key(|l| l.node);
    pd.load_of = vec![u32::MAX; node.len()];
    for (k, l) in pd.loads.iter().enumerate().rev() {
        pd.load_of[l.node as usize] = k as u32;
    }
    pd.contact = d.contact;
    pd.self_contact = d.self_contact;
    pd.kinematic = d.kinematic;
    pd.halo_nodes = node.len() - owned;

    // state: nodes, element resultants and force slots of these elements
    let pick3 = |v: &[Vec3]| -> Vec<Vec3> { node.iter().map(|&n| v[n as usize]).collect() };
    let shell = element.iter().map(|&e| s.shell[e as usize]).collect();
    let hourglass = quads
        .iter()
        .filter_map(|&e| s.hourglass.get(e as usize - nt).copied())
        .collect();
    // slots of element e start at 3e (triangles) or 3 nt + 4 (e - nt) (quads); with
    // Kelvin damping the second half repeats the layout
    let first_slot = |e: usize| if e < nt { 3 * e } else { 3 * nt + 4 * (e - nt) };
    let corners = |e: usize| if e < nt { 3 } else { 4 };
    let whole_half = d.gather_slot.len();
    // a whole that carries its forces as node sums gives them settled (`summed`)
    let whole_slots = crate::summed::slots_of(d, s);
    let halves = whole_slots.len() / whole_half.max(1);
    let mut slots = Vec::with_capacity(halves * b.def.gather_slot.len());
    for half in 0..halves {
        for &e in element {
            let a = half * whole_half + first_slot(e as usize);
            slots.extend_from_slice(&whole_slots[a..a + corners(e as usize)]);
        }
    }
    let f_contact = if s.f_contact.is_empty() {
        Vec::new()
    } else {
        pick3(&s.f_contact)
    };
    let state = BodyState {
        x: pick3(&s.x),
        v: pick3(&s.v),
        w: pick3(&s.w),
        shell,
        hourglass,
        slots,
        node_sums: Vec::new(),
        f_contact,
        energy: Default::default(),
        internal_now: 0.0,
        hourglass_now: 0.0,
    };
    Body::from_parts(Arc::clone(&b.def), state)
}
