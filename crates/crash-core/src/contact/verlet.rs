//! Per-node candidate lists (Verlet lists) of a node pass: each node keeps the segments
//! whose tree box meets a cube around it that is a little larger than its query, and
//! answers later queries from that list for as long as the query cube stays inside the
//! list's cube and the tree is the same build. One tree query per node every many steps
//! instead of two every step (the search and the crossing check): the R-tree walk was
//! about half of the contact stage.
//!
//! Exact, not approximate: the list holds every segment whose stored box meets the
//! list's cube; a query cube inside it is met only by boxes that meet the list's cube,
//! and the list is filtered by the very test the tree applies (inclusive box overlap on
//! the same stored corners). So a query answers the same set of segments from the list
//! as from the tree, and every result keeps its bits.

use super::surface::Surface;
use crate::Vec3;

/// One query's list (a node's, or a slave segment's in the segment pass): the box it was
/// made for, the tree build it came from, its segments.
#[derive(Debug, Clone)]
pub struct NodeList {
    lo: [f64; 3],
    hi: [f64; 3],
    build: u64,
    segs: Vec<u32>,
}

impl Default for NodeList {
    fn default() -> Self {
        Self {
            lo: [0.0; 3],
            hi: [0.0; 3],
            build: u64::MAX, // no tree has this id: the first query renews the list
            segs: Vec::new(),
        }
    }
}

/// The lists of one pass (node body, segment body), one per node.
#[derive(Debug, Clone, Default)]
pub struct NodeLists {
    lists: Vec<NodeList>,
}

impl NodeLists {
    /// The lists of a body of `n` nodes (renewed if the body changed size).
    pub fn fit(&mut self, n: usize) -> &mut [NodeList] {
        if self.lists.len() != n {
            self.lists = vec![NodeList::default(); n];
        }
        &mut self.lists
    }

    /// The chunks of `chunk` nodes of positions `x`, with their lists, for which
    /// `keep(chunk index)` holds, in chunk order. A node pass hands only these to the
    /// pool: a task per chunk, most of them far from the other body and empty, cost more
    /// in stolen tasks at 2 threads than the work (the crossing check of the OpenRadioss
    /// triangle model ran 1.8x slower on two threads than on one).
    pub fn live_chunks<'a>(
        &'a mut self,
        x: &'a [Vec3],
        chunk: usize,
        keep: impl Fn(usize) -> bool,
    ) -> Vec<(usize, &'a [Vec3], &'a mut [NodeList])> {
        x.chunks(chunk)
            .zip(self.fit(x.len()).chunks_mut(chunk))
            .enumerate()
            .filter(|(ci, _)| keep(*ci))
            .map(|(ci, (xs, l))| (ci, xs, l))
            .collect()
    }
}

/// The segment pass's lists of one direction (slave body, master body): one per slave
/// segment that passed the pass's box test, by segment index. Only those are kept: a
/// list per segment of the body would cost 80 bytes a segment for every body it ever
/// came near (a floor under many bodies), where the contact region needs a few hundred.
#[derive(Debug, Clone, Default)]
pub struct SegmentLists {
    lists: Vec<(u32, NodeList)>,
}

impl SegmentLists {
    /// The lists of `segs` (ascending), in that order: each segment's kept list, a new
    /// one for a segment that did not pass last time; the lists of segments not in
    /// `segs` are dropped.
    pub fn for_segments(&mut self, segs: &[u32]) -> Vec<&mut NodeList> {
        let kept = std::mem::replace(&mut self.lists, Vec::with_capacity(segs.len()));
        let mut old = kept.into_iter().peekable();
        for &j in segs {
            while old.next_if(|(k, _)| *k < j).is_some() {}
            let list = old
                .next_if(|(k, _)| *k == j)
                .map_or_else(NodeList::default, |(_, l)| l);
            self.lists.push((j, list));
        }
        self.lists.iter_mut().map(|(_, l)| l).collect()
    }
}

/// The segment pass's kept lists of one pair (a, b): each direction's slave-segment
/// lists (a's against b, b's against a) and the near sets' queries
/// (`reach::near_sets`): a's and b's first round, a's and b's second (both bodies are
/// queried in the first round, the one with the smaller loose bulge bound again in the
/// second; which one that is can change between passes).
#[derive(Debug, Clone, Default)]
pub struct PairLists {
    pub a: SegmentLists,
    pub b: SegmentLists,
    pub near: [NodeList; 4],
}

/// How much larger than its query a node's cube is, as a share of the tree's skin:
/// larger lists are renewed less often but hold more segments to filter.
pub const GROW: f64 = 0.25;

/// The segments of `surf` whose stored box meets the cube of half-size `r` around `p`,
/// into `out` (in no particular order): from the node's `list` when it covers the
/// query, else from the tree, renewing the list for queries up to half-size `reach`
/// (the search's: the crossing check's smaller ones then fit in it too).
pub fn candidates(
    list: &mut NodeList,
    surf: &Surface,
    p: &Vec3,
    r: f64,
    reach: f64,
    out: &mut Vec<u32>,
) {
    // the query's corners, computed as the tree query computes them
    let qlo = [p.x - r, p.y - r, p.z - r];
    let qhi = [p.x + r, p.y + r, p.z + r];
    box_candidates(list, surf, (&qlo, &qhi), out, false, || {
        let g = r.max(reach) + GROW * surf.skin();
        ([p.x - g, p.y - g, p.z - g], [p.x + g, p.y + g, p.z + g])
    });
}

/// The segments of `surf` whose stored box meets the box `qlo`..`qhi`, into `out` (in
/// the list's order: the tree's, or ascending with `sorted`): from `list` when its box
/// holds the query and it came from the current tree, else from the tree, the list
/// renewed for the box `renew` gives (which must hold the query).
fn box_candidates(
    list: &mut NodeList,
    surf: &Surface,
    (qlo, qhi): (&[f64; 3], &[f64; 3]),
    out: &mut Vec<u32>,
    sorted: bool,
    renew: impl FnOnce() -> ([f64; 3], [f64; 3]),
) {
    let covered = list.build == surf.tree_id()
        && (0..3).all(|d| list.lo[d] <= qlo[d] && qhi[d] <= list.hi[d]);
    if !covered {
        (list.lo, list.hi) = renew();
        list.build = surf.tree_id();
        surf.query(list.lo, list.hi, &mut list.segs);
        if sorted {
            list.segs.sort_unstable();
        }
    }
    out.clear();
    out.extend(
        list.segs
            .iter()
            .copied()
            .filter(|&j| surf.box_meets(j, qlo, qhi)),
    );
}

/// The segments of `surf` whose stored box meets the box `qlo`..`qhi`, ascending, into
/// `out`, from `list` (renewed as `box_candidates` does, for the query grown by
/// `GROW` times the tree's skin on every side): the segment pass's masters of a slave
/// segment, asked every step while the two bodies move less than that.
pub fn box_list(
    list: &mut NodeList,
    surf: &Surface,
    (qlo, qhi): (&[f64; 3], &[f64; 3]),
    out: &mut Vec<u32>,
) {
    box_candidates(list, surf, (qlo, qhi), out, true, || {
        let g = GROW * surf.skin();
        (
            std::array::from_fn(|d| qlo[d] - g),
            std::array::from_fn(|d| qhi[d] + g),
        )
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::{plate, ElementKind};
    use crate::{Body, Material, Section, Stabilization};

    /// A plate of `kind` rising and sinking over 2000 steps (its tree rebuilt now and
    /// then), `ask(k, t, z, surface)` at each step (z: how far it moved up); returns how
    /// often the tree was rebuilt.
    fn over_a_moving_plate(
        kind: ElementKind,
        mut ask: impl FnMut(usize, f64, f64, &Surface),
    ) -> usize {
        let mut b = Body::new(
            0,
            "plate",
            &plate(0.1, 0.1, 20, 20, kind),
            Section::new(Material::steel(), 0.001),
            Stabilization::default(),
        )
        .expect("plate");
        let skin = 1e-3;
        let mut surf = Surface::new(&b);
        let (mut rebuilds, mut z) = (0, 0.0);
        for k in 0..2000 {
            let t = k as f64 * 1e-3;
            let dz = 1e-5 * (t * 3.0).cos();
            z += dz;
            for x in &mut b.state.x {
                x.z += dz;
            }
            if surf.refresh(&b, skin) {
                rebuilds += 1;
            }
            ask(k, t, z, &surf);
        }
        rebuilds
    }

    /// A node wandering over a plate, and the plate itself moving (so the tree is
    /// rebuilt now and then): every query answers the tree's set, from the list or not.
    #[test]
    fn node_lists_answer_exactly_the_segments_the_tree_answers() {
        let mut list = NodeList::default();
        let (mut from_list, mut found) = (0, 0);
        let (mut a, mut want) = (Vec::new(), Vec::new());
        let rebuilds = over_a_moving_plate(ElementKind::Quad, |k, t, z, surf| {
            // hovering over the plate, at times out of reach
            let h = 4e-4 + 2e-3 * (0.7 * t).sin().max(0.0);
            let p = Vec3::new(0.03 * t.sin(), 0.02 * (1.7 * t).cos(), z + h);
            let r = if k % 3 == 0 { 5e-4 } else { 1e-5 };
            let before = (list.build, list.lo);
            candidates(&mut list, surf, &p, r, 5e-4, &mut a);
            from_list += usize::from(before == (list.build, list.lo));
            surf.candidates(&p, r, &mut want);
            a.sort_unstable();
            want.sort_unstable();
            assert_eq!(a, want, "query {k}");
            found += usize::from(!want.is_empty());
        });
        assert!(found > 500 && found < 1990, "{found}");
        // both paths taken many times
        assert!(from_list > 1000 && from_list < 1990, "{from_list}");
        assert!(rebuilds > 1, "{rebuilds}");
    }

    /// A slave segment's box wandering over a moving plate (the tree rebuilt now and
    /// then): every `box_list` answers the tree's set, ascending, from the list or not.
    #[test]
    fn segment_lists_answer_exactly_the_segments_the_tree_answers_ascending() {
        let mut list = NodeList::default();
        let (mut from_list, mut found) = (0, 0);
        let (mut a, mut want) = (Vec::new(), Vec::new());
        let rebuilds = over_a_moving_plate(ElementKind::Tri, |k, t, z, surf| {
            let c = Vec3::new(0.03 * t.sin(), 0.02 * (1.7 * t).cos(), z + 2e-3 * t.sin());
            let h = if k % 5 == 0 { 3e-3 } else { 1e-3 };
            let lo = [c.x - h, c.y - 0.5 * h, c.z - 2e-4];
            let hi = [c.x + h, c.y + 0.5 * h, c.z + 2e-4];
            let before = (list.build, list.lo);
            box_list(&mut list, surf, (&lo, &hi), &mut a);
            from_list += usize::from(before == (list.build, list.lo));
            surf.query(lo, hi, &mut want);
            want.sort_unstable();
            assert_eq!(a, want, "query {k}");
            found += usize::from(!want.is_empty());
        });
        assert!(found > 500 && found < 1990, "{found}");
        assert!(from_list > 500 && from_list < 1990, "{from_list}");
        assert!(rebuilds > 1, "{rebuilds}");
    }

    /// A segment that passes again finds its list; new ones start empty; the others'
    /// lists are dropped.
    #[test]
    fn segment_lists_follow_the_passing_segments() {
        let mut sl = SegmentLists::default();
        for (k, l) in sl.for_segments(&[1, 3, 5]).into_iter().enumerate() {
            l.build = 10 + k as u64;
        }
        let builds: Vec<u64> = sl
            .for_segments(&[2, 3, 6])
            .iter()
            .map(|l| l.build)
            .collect();
        assert_eq!(builds, [u64::MAX, 11, u64::MAX]);
        assert!(sl.for_segments(&[]).is_empty());
        assert!(sl.lists.is_empty());
    }
}
