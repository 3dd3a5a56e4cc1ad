//! History nodes (LS-DYNA NODOUT): displacement, velocity and acceleration of chosen
//! nodes after a step, taken by the group that integrates their body.

use crate::body::Body;
use crate::Vec3;
use serde::{Deserialize, Serialize};

/// One history node after the step from t_n to t_{n+1}: displacement x_{n+1} - x_0,
/// velocity v_{n+1/2}, acceleration a_n = (v_{n+1/2} - v_{n-1/2}) / hbar_n (zero at
/// the start), translational [m, m/s, m/s^2].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NodeProbe {
    pub body: u32,
    pub node: u32,
    pub u: Vec3,
    pub v: Vec3,
    pub a: Vec3,
}

/// The probed nodes of `body` in a list of (body id, node) sorted by body.
pub fn nodes_of(probes: &[(u32, u32)], body: u32) -> &[(u32, u32)] {
    let lo = probes.partition_point(|p| p.0 < body);
    let hi = probes.partition_point(|p| p.0 <= body);
    &probes[lo..hi]
}

impl Body {
    /// Velocities of the probed nodes (before a step; nodes outside the body skipped).
    pub fn probe_velocities(&self, nodes: &[(u32, u32)]) -> Vec<Vec3> {
        nodes
            .iter()
            .filter_map(|p| self.state.v.get(p.1 as usize).copied())
            .collect()
    }

    /// Probe rows after a step with mean step `hbar` (0: the start, no acceleration),
    /// from the velocities before it.
    pub fn probe(
        &self,
        nodes: &[(u32, u32)],
        before: &[Vec3],
        hbar: f64,
        out: &mut Vec<NodeProbe>,
    ) {
        let (d, s) = (&*self.def, &self.state);
        let inside = nodes.iter().filter(|p| (p.1 as usize) < s.x.len());
        for (p, vb) in inside.zip(before) {
            let i = p.1 as usize;
            let a = if hbar > 0.0 {
                (s.v[i] - vb) / hbar
            } else {
                Vec3::zeros()
            };
            out.push(NodeProbe {
                body: d.id,
                node: p.1,
                u: s.x[i] - d.x0[i],
                v: s.v[i],
                a,
            });
        }
    }
}
