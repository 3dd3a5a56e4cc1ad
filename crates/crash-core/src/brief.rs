//! What a coordinator keeps of a body: a few numbers and its box, no nodal data.

use crate::body::{Body, VelocityProgram};
use crate::contact::BodyBox;
use crate::curve::TimeCurve;
use crate::Vec3;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyBrief {
    pub id: u32,
    /// The scene's name of the body (for messages: groups named by their bodies).
    #[serde(default)]
    pub name: String,
    pub thickness: f64,
    /// Takes part in contact.
    pub contact: bool,
    /// Every DOF constrained (computes no internal forces).
    pub kinematic: bool,
    /// The velocity programs of a kinematic body (empty otherwise): the coordinator
    /// counts the work contact does on it (`KinematicWork`).
    #[serde(default)]
    pub programs: Vec<VelocityProgram>,
    /// The load curves its programs use (kinematic bodies only).
    #[serde(default)]
    pub curves: Vec<TimeCurve>,
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
            name: b.def.name.clone(),
            thickness: b.def.section.thickness,
            contact: b.def.contact,
            kinematic: b.def.kinematic,
            programs: if b.def.kinematic {
                b.def.programs.clone()
            } else {
                Vec::new()
            },
            curves: if b.def.kinematic {
                b.def.curves.clone()
            } else {
                Vec::new()
            },
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
