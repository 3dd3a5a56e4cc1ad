//! What a coordinator keeps of a body: a few numbers and its box, no nodal data.

use crate::body::Body;
use crate::contact::BodyBox;
use crate::Vec3;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BodyBrief {
    pub id: u32,
    pub thickness: f64,
    /// Takes part in contact.
    pub contact: bool,
    /// Every DOF constrained (computes no internal forces).
    pub kinematic: bool,
    pub nodes: usize,
    pub elements: usize,
    /// Bounding box of the nodes.
    pub lo: Vec3,
    pub hi: Vec3,
}

impl BodyBrief {
    pub fn of(b: &Body) -> Self {
        let bbox = BodyBox::of(b);
        Self {
            id: b.def.id,
            thickness: b.def.section.thickness,
            contact: b.def.contact,
            kinematic: b.def.kinematic,
            nodes: b.node_count(),
            elements: b.element_count(),
            lo: bbox.lo,
            hi: bbox.hi,
        }
    }

    /// The contact search box (the same as `BodyBox::of` the body).
    pub fn bbox(&self) -> BodyBox {
        BodyBox {
            id: self.id,
            lo: self.lo,
            hi: self.hi,
            thickness: self.thickness,
        }
    }
}
