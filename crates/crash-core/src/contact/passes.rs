//! The node passes of one candidate pair: per pass (the nodes of one body against the
//! segments of the other) the crossing check, then the search. The two passes of a pair
//! of different bodies run at once on the pool: each keeps its own node lists, and
//! together their live chunks fill both threads where one pass's few chunks near the
//! other body left a thread waiting (the showcase's plate has about ten such chunks, its
//! sphere fewer).
//!
//! Same results as one pass after the other: a pass reads only the positions and its
//! own lists (a cache, exact: `verlet.rs`), and the fault is the first pass's crossing
//! if it has one, else the second's, as when the first pass ran first.

use super::narrow::{search, Hit};
use super::surface::Surface;
use super::sweep::{first_crossing, Crossing};
use super::verlet::NodeLists;
use crate::body::Body;
use crate::error::Fault;
use std::collections::BTreeMap;

/// The hits of a pair's passes: nodes of a against segments of b, then the reverse
/// (empty for a self pair).
pub(crate) type PairHits = (Vec<Hit>, Vec<Hit>);

/// One pass: its crossing check, then (`find`, and no crossing) its search.
#[allow(clippy::too_many_arguments)]
fn pass(
    nb: &Body,
    ns: &Surface,
    sb: &Body,
    ss: &Surface,
    self_pass: bool,
    h: f64,
    lists: &mut NodeLists,
    find: bool,
) -> Result<Vec<Hit>, Crossing> {
    if let Some(c) = first_crossing(nb, &ns.chunks, sb, ss, self_pass, h, lists) {
        return Err(c);
    }
    Ok(if find {
        search(nb, &ns.chunks, sb, ss, self_pass, lists)
    } else {
        Vec::new()
    })
}

/// The crossing check of both passes of pair (a, b) as a fault naming both bodies, and
/// when `find` their hits. `lists`: the node lists per (node body, segment body).
#[allow(clippy::too_many_arguments)]
pub(crate) fn pair_passes(
    a: &Body,
    b: &Body,
    sa: &Surface,
    sb: &Surface,
    lists: &mut BTreeMap<(u32, u32), NodeLists>,
    h: f64,
    step: u64,
    find: bool,
) -> Result<PairHits, Fault> {
    let (ia, ib) = (a.def.id, b.def.id);
    let fault = |nb: &Body, other: &Body, c: Crossing| Fault::PassThrough {
        step,
        body: nb.def.id,
        body_name: nb.def.name.clone(),
        node: c.node,
        other: other.def.id,
        other_name: other.def.name.clone(),
        segment: c.segment,
        closing_speed: c.closing_speed,
    };
    if ia == ib {
        let l = lists.entry((ia, ib)).or_default();
        let hits = pass(a, sa, b, sb, true, h, l, find).map_err(|c| fault(a, b, c))?;
        return Ok((hits, Vec::new()));
    }
    // the two lists out of the map for the join, back in after
    let mut la = lists.remove(&(ia, ib)).unwrap_or_default();
    let mut lb = lists.remove(&(ib, ia)).unwrap_or_default();
    let (first, second) = rayon::join(
        || pass(a, sa, b, sb, false, h, &mut la, find),
        || pass(b, sb, a, sa, false, h, &mut lb, find),
    );
    lists.insert((ia, ib), la);
    lists.insert((ib, ia), lb);
    let first = first.map_err(|c| fault(a, b, c))?;
    let second = second.map_err(|c| fault(b, a, c))?;
    Ok((first, second))
}
