//! The reports of a group shared between workers: each holder's share of a body's
//! report merged into one (`merge_report`), and faults of a part named in the whole
//! body's numbers.

use crate::body::BodyEnergy;
use crate::error::{place_index, Fault};
use crate::group::{BodyReport, Reaction};

/// Join two holders' shares of one body's report: energies summed (another order than
/// the whole body's: ulps), the box and the move order-free, the element step and hot
/// element by value then lowest element.
pub fn merge_report(a: BodyReport, b: BodyReport) -> BodyReport {
    let (dt, dt_element) = if b.stable_dt < a.stable_dt
        || (b.stable_dt == a.stable_dt && b.dt_element < a.dt_element)
    {
        (b.stable_dt, b.dt_element)
    } else {
        (a.stable_dt, a.dt_element)
    };
    let (hot_density, hot_element) = if b.hot_density > a.hot_density
        || (b.hot_density == a.hot_density && b.hot_element < a.hot_element)
    {
        (b.hot_density, b.hot_element)
    } else {
        (a.hot_density, a.hot_element)
    };
    let reaction = match (a.reaction, b.reaction) {
        (Some(x), Some(y)) => Some(add_reaction(x, y)),
        (x, y) => x.or(y),
    };
    BodyReport {
        id: a.id,
        energy: add_energy(a.energy, b.energy),
        stable_dt: dt,
        dt_element,
        lo: a.lo.inf(&b.lo),
        hi: a.hi.sup(&b.hi),
        max_move: a.max_move.max(b.max_move),
        hot_element,
        hot_density,
        reaction,
    }
}

pub(super) fn add_energy(a: BodyEnergy, b: BodyEnergy) -> BodyEnergy {
    BodyEnergy {
        kinetic: a.kinetic + b.kinetic,
        internal: a.internal + b.internal,
        hourglass: a.hourglass + b.hourglass,
        contact: a.contact + b.contact,
        damping: a.damping + b.damping,
        external: a.external + b.external,
    }
}

pub(super) fn add_reaction(a: Reaction, b: Reaction) -> Reaction {
    Reaction {
        force: a.force + b.force,
        moment: a.moment + b.moment,
        moment_origin: a.moment_origin + b.moment_origin,
    }
}

/// A fault of a part's integration with the whole body's node number.
pub(super) fn node_in_whole(mut f: Fault, node: &[u32]) -> Fault {
    if let Fault::NonFinite { place, .. } = &mut f {
        if let Some(n) = place_index(place, "node") {
            if let Some(&g) = node.get(n) {
                *place = format!("node {g}");
            }
        }
    }
    f
}

/// A fault of a part's element pass with the whole body's element number.
pub(super) fn element_in_whole(mut f: Fault, element: &[u32]) -> Fault {
    let map = |e: &mut usize| {
        if let Some(&g) = element.get(*e) {
            *e = g as usize;
        }
    };
    match &mut f {
        Fault::Collapsed { element: e, .. } | Fault::Inverted { element: e, .. } => map(e),
        Fault::NonFinite { place, .. } => {
            if let Some(n) = place_index(place, "element") {
                if let Some(&g) = element.get(n) {
                    *place = format!("element {g}");
                }
            }
        }
        _ => {}
    }
    f
}
