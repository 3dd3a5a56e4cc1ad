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

/// What the passes of one pair are asked to do: the pair's body indices, and whether
/// the search follows the crossing check (`find`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PairJob {
    pub ia: usize,
    pub ib: usize,
    pub find: bool,
}

/// The passes of every pair of `jobs` at once on the pool, with the hits of each pair in
/// `jobs` order. Pairs of a floor under many small bodies each hold a few chunks of
/// work: one after the other they paid a fork-join each and left a thread idle.
///
/// Same results as pair after pair: a pass reads positions, surfaces and its own node
/// lists only (each (node body, segment body) list belongs to one pass of one pair), and
/// the fault is that of the first pair in `jobs` order that has one, as when the pairs
/// ran in that order (the later pairs' lists are refreshed too, a cache: exact either way).
pub(crate) fn all_pair_passes(
    bodies: &[Body],
    surfaces: &BTreeMap<u32, Surface>,
    lists: &mut BTreeMap<(u32, u32), NodeLists>,
    jobs: &[PairJob],
    h: f64,
    step: u64,
) -> Result<Vec<PairHits>, Fault> {
    use rayon::prelude::*;
    let ids = |j: &PairJob| (bodies[j.ia].def.id, bodies[j.ib].def.id);
    // every pair's lists out of the map (their keys are distinct: pairs are), back after
    let mut own: Vec<(NodeLists, NodeLists)> = jobs
        .iter()
        .map(|j| {
            let (a, b) = ids(j);
            let la = lists.remove(&(a, b)).unwrap_or_default();
            let lb = if a == b {
                NodeLists::default()
            } else {
                lists.remove(&(b, a)).unwrap_or_default()
            };
            (la, lb)
        })
        .collect();
    let out: Vec<Result<PairHits, Fault>> = jobs
        .par_iter()
        .zip(own.par_iter_mut())
        .map(|(j, (la, lb))| {
            let (a, b) = (&bodies[j.ia], &bodies[j.ib]);
            match (surfaces.get(&a.def.id), surfaces.get(&b.def.id)) {
                (Some(sa), Some(sb)) => pair_passes(a, b, sa, sb, la, lb, h, step, j.find),
                _ => Ok((Vec::new(), Vec::new())),
            }
        })
        .collect();
    for (j, (la, lb)) in jobs.iter().zip(own) {
        let (a, b) = ids(j);
        lists.insert((a, b), la);
        if a != b {
            lists.insert((b, a), lb);
        }
    }
    out.into_iter().collect()
}

/// The crossing check of both passes of pair (a, b) as a fault naming both bodies, and
/// when `find` their hits. `la`, `lb`: the node lists of a's nodes against b's segments
/// and the reverse (`lb` unused for a self pair).
#[allow(clippy::too_many_arguments)]
fn pair_passes(
    a: &Body,
    b: &Body,
    sa: &Surface,
    sb: &Surface,
    la: &mut NodeLists,
    lb: &mut NodeLists,
    h: f64,
    step: u64,
    find: bool,
) -> Result<PairHits, Fault> {
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
    if a.def.id == b.def.id {
        let hits = pass(a, sa, b, sb, true, h, la, find).map_err(|c| fault(a, b, c))?;
        return Ok((hits, Vec::new()));
    }
    let (first, second) = rayon::join(
        || pass(a, sa, b, sb, false, h, la, find),
        || pass(b, sb, a, sa, false, h, lb, find),
    );
    let first = first.map_err(|c| fault(a, b, c))?;
    let second = second.map_err(|c| fault(b, a, c))?;
    Ok((first, second))
}
