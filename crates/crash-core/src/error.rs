//! Typed errors: bad input (`CoreError`) and run-time faults (`Fault`).

use thiserror::Error;

/// Invalid input to the physics core (material, mesh, boundary conditions).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CoreError {
    #[error("material: {field} = {value} is invalid: {valid}")]
    Material {
        field: &'static str,
        value: f64,
        valid: &'static str,
    },
    #[error("body '{body}': thickness = {value} is invalid: must be finite and > 0")]
    Thickness { body: String, value: f64 },
    #[error(
        "body '{body}': element {element} refers to node {node}, but the body has {nodes} nodes"
    )]
    NodeIndex {
        body: String,
        element: usize,
        node: u32,
        nodes: usize,
    },
    #[error("body '{body}': element {element} is degenerate (area {area:.3e} m^2, repeated or collinear nodes)")]
    Degenerate {
        body: String,
        element: usize,
        area: f64,
    },
    #[error("body '{body}': quad {element} is warped by {warp:.3} (max out-of-plane offset / sqrt(area)); the one-point quad is valid up to {limit}: split it into triangles")]
    Warped {
        body: String,
        element: usize,
        warp: f64,
        limit: f64,
    },
    #[error("body '{body}': quad {element} is not convex (corner {corner} turns the wrong way)")]
    NonConvex {
        body: String,
        element: usize,
        corner: usize,
    },
    #[error("body '{body}': node {node} has a non-finite coordinate")]
    NonFiniteNode { body: String, node: usize },
    #[error("body '{body}' has no elements")]
    Empty { body: String },
    #[error("body '{body}': {what}")]
    Other { body: String, what: String },
}

/// Why a run stopped: every variant names the body, the place and the step.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Fault {
    #[error("step {step}: non-finite {what} in body {body} ({place}); the time step is probably too large or an input is extreme")]
    NonFinite {
        step: u64,
        body: u32,
        place: String,
        what: &'static str,
    },
    #[error("step {step}: element {element} of body {body} collapsed (area ratio {ratio:.3e} of its initial area)")]
    Collapsed {
        step: u64,
        body: u32,
        element: usize,
        ratio: f64,
    },
    #[error("step {step}: element {element} of body {body} is inverted (corner {corner} turned inside out)")]
    Inverted {
        step: u64,
        body: u32,
        element: usize,
        corner: usize,
    },
    #[error("step {step}: energy runaway: the run's energy-balance error {:.2}% of its largest energy exceeds the scene's energy_limit {:.2}% for more than 3 steps; the most strained element is {element} of body {body} (usually: a time step above the critical one, a too stiff penalty, or an impact that crushes the mesh)", .error * 100.0, .limit * 100.0)]
    EnergyRunaway {
        step: u64,
        error: f64,
        limit: f64,
        body: u32,
        element: usize,
    },
    #[error("step {step}: time step collapsed to {dt:.3e} s (below the floor {floor:.3e} s) at element {element} of body {body}")]
    DtCollapse {
        step: u64,
        dt: f64,
        floor: f64,
        body: u32,
        element: usize,
    },
    #[error("step {step}: node {node} of body {body} moved {distance:.3e} m in one step (speed {speed:.3e} m/s), more than the contact search margin budget {budget:.3e} m allows; contact could be missed: increase the margin or lower the time step")]
    Tunnelling {
        step: u64,
        body: u32,
        node: usize,
        speed: f64,
        distance: f64,
        budget: f64,
    },
    #[error("step {step}: node {node} of body '{body_name}' (#{body}) passed through the mid-surface of body '{other_name}' (#{other}, segment {segment}) at a closing speed of {closing_speed:.3e} m/s: the contact did not hold; the results after this point would be wrong (lower dt_safety, use contact.speed_rule = \"limit_dt\", raise the penalty scale, or under the segment pass set contact.sides = \"both\")")]
    PassThrough {
        step: u64,
        body: u32,
        body_name: String,
        node: usize,
        other: u32,
        other_name: String,
        segment: usize,
        /// Normal relative speed of the node and the segment point it crossed [m/s].
        closing_speed: f64,
    },
}

/// The number in a `NonFinite` fault's place of `kind` ("node" or "element"), e.g.
/// 12 of "node 12"; None for another kind.
pub fn place_index(place: &str, kind: &str) -> Option<usize> {
    place.strip_prefix(kind)?.strip_prefix(' ')?.parse().ok()
}

impl Fault {
    /// Where the fault sits in the order in which one process finds faults: its step,
    /// its body, then its node or element (a body's nodes and elements are stepped in
    /// index order, so the lowest comes first). A body split into parts finds its
    /// faults part by part, possibly on several workers: the first of them in this
    /// order is the one process's fault (`partition`, crash-master's barrier).
    pub fn order(&self) -> (u64, u32, usize) {
        match self {
            Fault::NonFinite {
                step, body, place, ..
            } => {
                let i = place_index(place, "node").or_else(|| place_index(place, "element"));
                (*step, *body, i.unwrap_or(0))
            }
            Fault::Collapsed {
                step,
                body,
                element,
                ..
            }
            | Fault::Inverted {
                step,
                body,
                element,
                ..
            }
            | Fault::EnergyRunaway {
                step,
                body,
                element,
                ..
            }
            | Fault::DtCollapse {
                step,
                body,
                element,
                ..
            } => (*step, *body, *element),
            Fault::Tunnelling {
                step, body, node, ..
            }
            | Fault::PassThrough {
                step, body, node, ..
            } => (*step, *body, *node),
        }
    }

    /// The one of `a` and `b` that comes first in `order` (`a` on a tie).
    pub fn first_of(a: Option<Fault>, b: Fault) -> Fault {
        match a {
            Some(a) if a.order() <= b.order() => a,
            _ => b,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn non_finite(step: u64, body: u32, place: &str) -> Fault {
        Fault::NonFinite {
            step,
            body,
            place: place.into(),
            what: "velocity or position",
        }
    }

    #[test]
    fn the_first_fault_is_the_earliest_step_then_the_lowest_body_then_the_lowest_index() {
        let node19 = non_finite(66, 2, "node 19");
        let node0 = non_finite(66, 2, "node 0");
        assert_eq!(Fault::first_of(Some(node19.clone()), node0.clone()), node0);
        assert_eq!(Fault::first_of(Some(node0.clone()), node19.clone()), node0);
        assert_eq!(Fault::first_of(None, node19.clone()), node19);
        let body1 = non_finite(66, 1, "node 300");
        assert_eq!(Fault::first_of(Some(node0.clone()), body1.clone()), body1);
        let earlier = Fault::Collapsed {
            step: 65,
            body: 3,
            element: 7,
            ratio: 1e-3,
        };
        assert_eq!(Fault::first_of(Some(node0), earlier.clone()), earlier);
        assert_eq!(non_finite(1, 0, "element 12").order(), (1, 0, 12));
    }
}
