//! What `crash check` prints: bodies, nodes, elements, masses, constraints and the run
//! parameters, with a time step estimate (the core's first force pass gives the exact one).

use crate::build::Built;
use crate::margin::{dt_estimate, min_length};
use std::fmt;

#[derive(Debug, Clone, PartialEq)]
pub struct BodySummary {
    pub id: u32,
    pub name: String,
    pub shape: String,
    pub material: String,
    pub thickness: f64,
    pub nodes: usize,
    pub tris: usize,
    pub quads: usize,
    /// [kg]
    pub mass: f64,
    pub fixed_nodes: usize,
    pub prescribed_nodes: usize,
    pub loaded_nodes: usize,
    /// Smallest characteristic element length [m].
    pub min_length: f64,
    /// L_min / c (no safety factor) [s].
    pub dt_estimate: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    pub name: String,
    pub bodies: Vec<BodySummary>,
    pub nodes: usize,
    pub elements: usize,
    pub end_time: f64,
    pub safety: f64,
    pub output_interval: f64,
    pub margin: f64,
    pub margin_derived: bool,
    /// Smallest body estimate times the safety factor [s].
    pub dt_estimate: f64,
    /// end_time / dt_estimate.
    pub steps_estimate: f64,
}

impl Built {
    pub fn summary(&self) -> Summary {
        let bodies: Vec<BodySummary> = self
            .bodies
            .iter()
            .zip(&self.info)
            .map(|(b, i)| BodySummary {
                id: b.def.id,
                name: b.def.name.clone(),
                shape: i.shape.clone(),
                material: i.material.clone(),
                thickness: b.def.section.thickness,
                nodes: b.node_count(),
                tris: b.def.tris.len(),
                quads: b.def.quads.len(),
                mass: b.total_mass(),
                fixed_nodes: i.fixed_nodes,
                prescribed_nodes: i.prescribed_nodes,
                loaded_nodes: i.loaded_nodes,
                min_length: min_length(b),
                dt_estimate: dt_estimate(b),
            })
            .collect();
        let dt = self.safety
            * bodies
                .iter()
                .map(|b| b.dt_estimate)
                .fold(f64::INFINITY, f64::min);
        Summary {
            name: self.name.clone(),
            nodes: bodies.iter().map(|b| b.nodes).sum(),
            elements: bodies.iter().map(|b| b.tris + b.quads).sum(),
            bodies,
            end_time: self.end_time,
            safety: self.safety,
            output_interval: self.output_interval,
            margin: self.contact.margin,
            margin_derived: self.margin_derived,
            dt_estimate: dt,
            steps_estimate: self.end_time / dt,
        }
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "scene {}: {} bodies, {} nodes, {} elements",
            self.name,
            self.bodies.len(),
            self.nodes,
            self.elements
        )?;
        writeln!(
            f,
            "{:>3}  {:<16} {:<10} {:>9} {:>9} {:>9} {:>11} {:>7} {:>7} {:>7}  shape",
            "id",
            "name",
            "material",
            "t [m]",
            "nodes",
            "elements",
            "mass [kg]",
            "fixed",
            "moved",
            "loaded"
        )?;
        for b in &self.bodies {
            writeln!(
                f,
                "{:>3}  {:<16} {:<10} {:>9.3e} {:>9} {:>9} {:>11.4e} {:>7} {:>7} {:>7}  {}",
                b.id,
                b.name,
                b.material,
                b.thickness,
                b.nodes,
                b.tris + b.quads,
                b.mass,
                b.fixed_nodes,
                b.prescribed_nodes,
                b.loaded_nodes,
                b.shape
            )?;
        }
        writeln!(
            f,
            "end time {:.4e} s, output every {:.4e} s, dt safety {}",
            self.end_time, self.output_interval, self.safety
        )?;
        writeln!(
            f,
            "contact margin {:.4e} m ({})",
            self.margin,
            if self.margin_derived {
                "derived"
            } else {
                "given"
            }
        )?;
        write!(
            f,
            "time step estimate {:.4e} s (safety included), about {:.0} steps",
            self.dt_estimate, self.steps_estimate
        )
    }
}
