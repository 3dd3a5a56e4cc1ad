//! The segment pass of a pair (`ContactPass::Segments`): the slave body's points
//! (`quadrature.rs`) against the master's curved surface and their forces applied, in
//! point order, then the loads on the normals pulled back once per normal.
//! docs/theory-contact.md, "Segment pass".

use super::config::{ContactConfig, SegmentSides, ONE_SIDE_RATIO};
use super::curved::{normal_pullback, NormalOf};
use super::quadrature::BULGE_REACH;
use super::quadrature::{point_pushes, NormalLoad, PointPush, Points};
use super::reach::{near_sets, union};
use super::stats::{KinLoad, PairStats};
use super::surface::Surface;
use super::verlet::PairLists;
use crate::body::Body;
use crate::Vec3;
use std::collections::BTreeMap;
use std::mem::take;

/// How much finer (smaller mean initial segment area) one surface must be than the
/// other to be the slave; within it the lower id is. A margin, not an exact
/// comparison: two copies of one mesh at different places have areas that differ in
/// the last bits, and the rule must not hang on them.
const FINER: f64 = 0.99;

/// Whether body a (id, surface) is the slave of the pair's segment pass rather than b:
/// the finer surface, else the lower id. The figures are the whole bodies' (never a
/// view's segments), so every mode picks the same side.
pub(crate) fn slave_is_a((ida, sa): (u32, &Surface), (idb, sb): (u32, &Surface)) -> bool {
    let (ma, mb) = (sa.figures.mean_area, sb.figures.mean_area);
    if ma < FINER * mb {
        true
    } else if mb < FINER * ma {
        false
    } else {
        ida < idb
    }
}

/// Which points a pair's segment pass searches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Sides {
    /// a's points against b, full weight.
    A,
    /// b's points against a, full weight.
    B,
    /// Each body's points against the other, half the weight each.
    Both,
}

impl Sides {
    /// The sides of the pair (a, b) under `sides`: under `SegmentSides::Auto` one way
    /// only where one surface's mean initial segment area is below `ONE_SIDE_RATIO` of
    /// the other's. Whole-body figures, as `slave_is_a`: every mode decides alike.
    pub(crate) fn of(sides: SegmentSides, a: (u32, &Surface), b: (u32, &Surface)) -> Self {
        let one_way = match sides {
            SegmentSides::Both => false,
            SegmentSides::Finer => true,
            SegmentSides::Auto => {
                let (ma, mb) = (a.1.figures.mean_area, b.1.figures.mean_area);
                ma.min(mb) < ONE_SIDE_RATIO * ma.max(mb)
            }
        };
        match (one_way, slave_is_a(a, b)) {
            (false, _) => Sides::Both,
            (true, true) => Sides::A,
            (true, false) => Sides::B,
        }
    }

    /// The share of the stiffness each side's points carry.
    fn weight(self) -> f64 {
        match self {
            Sides::A | Sides::B => 1.0,
            Sides::Both => 0.5,
        }
    }
}

/// The segment pass of a pair of different bodies (indices `ia`, `ib`, surfaces `sa`,
/// `sb`): one way (`Sides::of`) the slave's points (`slave_is_a`) against the master's
/// curved surface, stiffness per unit area kappa = s mu / dt_ref^2 (the soft rule per
/// area, mu the lighter areal mass); two way each body's points against the other with
/// half of it. One side keeps issue 12's oblique bounds closer at
/// about half the cost; both hold sharp folds in a crush (docs/theory-contact.md,
/// "One side").
/// `counted`: which slave segments' points the statistics book, of a and of b (None:
/// all): a split group's views overlap, and each point is booked by the holder that
/// counts its slave segment's element. `slaves`: the slave segments searched, of a and
/// of b (None: all; a split group's view searches those that can push its owned nodes).
/// `lists`: the pair's lists kept from pass to pass (the slave segments' masters, a's
/// against b and b's against a, `quadrature::point_pushes`; the near sets' queries,
/// `reach::near_sets`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn segment_pair(
    bodies: &mut [Body],
    ia: usize,
    ib: usize,
    sa: &Surface,
    sb: &Surface,
    cfg: &ContactConfig,
    dt_ref: f64,
    counted: (Option<&[bool]>, Option<&[bool]>),
    slaves: (Option<&[bool]>, Option<&[bool]>),
    lists: &mut PairLists,
) -> PairStats {
    let (a, b) = (&bodies[ia], &bodies[ib]);
    let mu = sa.figures.areal_mass.min(sb.figures.areal_mass);
    let sides = Sides::of(cfg.sides, (a.def.id, sa), (b.def.id, sb));
    let kappa = sides.weight() * cfg.penalty_scale * mu / (dt_ref * dt_ref);
    let (first, second) = pair_points(a, sa, b, sb, cfg, sides, kappa, mu, slaves, lists);
    let mut st = PairStats::empty(a.def.id, b.def.id, 0);
    let thin = a.def.section.thickness.min(b.def.section.thickness);
    apply_points(bodies, (ia, ib), &first, &mut st, true, counted.0);
    apply_points(bodies, (ib, ia), &second, &mut st, false, counted.1);
    // the loads on each body's normals, summed per normal (in point order), then pulled
    // back once per normal in normal order
    let on_a = first
        .iter()
        .flat_map(|c| &c.slave_loads)
        .chain(second.iter().flat_map(|c| &c.master_loads));
    let on_b = first
        .iter()
        .flat_map(|c| &c.master_loads)
        .chain(second.iter().flat_map(|c| &c.slave_loads));
    let mut buf = Vec::new();
    for (ib_, loads, surf, is_a) in [
        (ia, on_a.collect::<Vec<_>>(), sa, true),
        (ib, on_b.collect(), sb, false),
    ] {
        buf.clear();
        pull_back_loads(&loads, surf, &bodies[ib_].state.x, &mut buf);
        let kin = if is_a { &mut st.kin_a } else { &mut st.kin_b };
        add_forces(&mut bodies[ib_], &buf, kin);
    }
    st.kin_a.settle_nodes();
    st.kin_b.settle_nodes();
    st.settle(thin);
    st
}

/// The loads on a body's normals summed per normal, each sum in load order from zero,
/// then pulled back to node forces once per normal in `NormalOf` order (nodes
/// ascending, then crease segments ascending), into `out`. The node loads are sorted by
/// node, then by their place in `loads`, and summed run by run: arrays the size of the
/// body (the sums before session 38) were zeroed for every pair and pass, about 8 % of
/// the segment pass on a plate under 64 spheres.
fn pull_back_loads(loads: &[&NormalLoad], surf: &Surface, x: &[Vec3], out: &mut Vec<(u32, Vec3)>) {
    let mut at_nodes: Vec<(u32, usize)> = Vec::new();
    let mut seg_sum: BTreeMap<u32, Vec3> = BTreeMap::new();
    for (i, l) in loads.iter().enumerate() {
        match l.of {
            NormalOf::Node(n) => at_nodes.push((n, i)),
            NormalOf::Segment(j) => *seg_sum.entry(j).or_insert_with(Vec3::zeros) += l.tau,
        }
    }
    // by node, then load order (the indices are unique)
    at_nodes.sort_unstable();
    for run in at_nodes.chunk_by(|a, b| a.0 == b.0) {
        let mut sum = Vec3::zeros();
        for &(_, i) in run {
            sum += loads[i].tau;
        }
        normal_pullback(NormalOf::Node(run[0].0), surf, x, &sum, out);
    }
    for (j, tau) in &seg_sum {
        normal_pullback(NormalOf::Segment(*j), surf, x, tau, out);
    }
}

/// Add node forces to a body's `f_contact` in order; on a kinematic body they go into
/// the pair's `KinLoad` too.
fn add_forces(b: &mut Body, forces: &[(u32, Vec3)], kin: &mut KinLoad) {
    let is_kin = b.def.kinematic;
    for &(n, f) in forces {
        b.state.f_contact[n as usize] += f;
        if is_kin {
            kin.push(n, f, b.state.v[n as usize], b.def.program[n as usize]);
        }
    }
}

/// Add the points of one direction of the segment pass: their node forces on the
/// slave's nodes (body `islave`) and the master's, sequentially in point order; what lands on
/// a kinematic body goes into the pair's `KinLoad` too. The statistics book the points
/// whose slave segment `counted` holds (every point without it).
fn apply_points(
    bodies: &mut [Body],
    (islave, imaster): (usize, usize),
    chunks: &[Points],
    st: &mut PairStats,
    slave_is_a: bool,
    counted: Option<&[bool]>,
) {
    let (mut l_s, mut l_m) = if slave_is_a {
        (take(&mut st.kin_a), take(&mut st.kin_b))
    } else {
        (take(&mut st.kin_b), take(&mut st.kin_a))
    };
    for p in chunks.iter().flat_map(|c| &c.pushes) {
        add_forces(
            &mut bodies[islave],
            &p.slave_f[..p.slave_count as usize],
            &mut l_s,
        );
        add_forces(
            &mut bodies[imaster],
            &p.master_f[..p.master_count as usize],
            &mut l_m,
        );
        if counted.is_none_or(|c| c.get(p.slave_seg as usize).copied().unwrap_or(false)) {
            st.active_nodes += 1;
            st.book(
                p.depth,
                p.normal_force,
                Some(if slave_is_a { p.force } else { -p.force }),
            );
        }
    }
    if slave_is_a {
        (st.kin_a, st.kin_b) = (l_s, l_m);
    } else {
        (st.kin_b, st.kin_a) = (l_s, l_m);
    }
}

/// The points of a pair at the current positions (a's against b, b's against a; one
/// way the master's direction has none), stiffness per unit area `kappa`, damping
/// areal mass `mu`.
#[allow(clippy::too_many_arguments)]
fn pair_points(
    a: &Body,
    sa: &Surface,
    b: &Body,
    sb: &Surface,
    cfg: &ContactConfig,
    sides: Sides,
    kappa: f64,
    mu: f64,
    slaves: (Option<&[bool]>, Option<&[bool]>),
    lists: &mut PairLists,
) -> (Vec<Points>, Vec<Points>) {
    // the segments of each body that can touch the other, their curved data and how far
    // each body's curved surface can stand off its facets there (exact bounds over those
    // segments, so the search misses no point of a coarse mesh): `reach::near_sets`.
    // Only segments whose tree box comes within 1.25 c plus both surfaces' loose bulge
    // bounds of the other body are read.
    let c = 0.5 * (a.def.section.thickness + b.def.section.thickness);
    let PairLists { a: la, b: lb, near } = lists;
    let (ca, cb) = near_sets(
        (sa, &a.state.x),
        (sb, &b.state.x),
        c * (1.0 + BULGE_REACH),
        near,
    );
    // the other's segments a point can touch lie in the box of the other's near set
    // (taken in the direction that runs: one side needs only the master's)
    let mut ab = || {
        point_pushes(
            a,
            sa,
            b,
            sb,
            union(cb.boxes()),
            (&ca, &cb),
            cfg,
            kappa,
            mu,
            slaves.0,
            la,
        )
    };
    let mut ba = || {
        point_pushes(
            b,
            sb,
            a,
            sa,
            union(ca.boxes()),
            (&cb, &ca),
            cfg,
            kappa,
            mu,
            slaves.1,
            lb,
        )
    };
    match sides {
        // the two directions at once (each reads only positions): the pool gets both
        // directions' tasks, and a direction with few points does not leave a thread idle
        Sides::Both => rayon::join(ab, ba),
        Sides::A => (ab(), Vec::new()),
        Sides::B => (Vec::new(), ba()),
    }
}

/// The segment pass's active points of a pair at the current positions, without
/// forces, per direction (a's points against b, b's against a; under one side the
/// master's direction has none): their number and the
/// deepest (for the check at t = 0: a curved surface can reach into another body where
/// no node does).
pub(crate) fn active_points(
    a: &Body,
    sa: &Surface,
    b: &Body,
    sb: &Surface,
    cfg: &ContactConfig,
) -> [(usize, Option<PointPush>); 2] {
    // any stiffness: which points are active depends on the gap alone
    let mu = sa.figures.areal_mass.min(sb.figures.areal_mass);
    let lists = &mut PairLists::default();
    let sides = Sides::of(cfg.sides, (a.def.id, sa), (b.def.id, sb));
    let (first, second) = pair_points(a, sa, b, sb, cfg, sides, 1.0, mu, (None, None), lists);
    [first, second].map(|chunks| {
        let pushes = chunks.into_iter().flat_map(|c| c.pushes);
        pushes.fold((0, None), |(n, deepest): (usize, Option<PointPush>), p| {
            let deeper = deepest.as_ref().is_none_or(|d| p.depth > d.depth);
            (n + 1, if deeper { Some(p) } else { deepest })
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Material, Section};
    use crate::mesh::Mesh;
    use crate::shapes::{icosphere, plate, ElementKind};
    use crate::Stabilization;

    fn surface(id: u32, mut m: Mesh, shift: Vec3) -> (u32, Surface) {
        m.transform(&nalgebra::Matrix3::identity(), shift);
        let section = Section::new(Material::steel(), 1e-3);
        let b = Body::new(id, "b", &m, section, Stabilization::default()).expect("valid body");
        (id, Surface::new(&b))
    }

    /// The slave is the finer surface whichever way round the pair is given, and
    /// between two copies of one mesh (areas equal but for round-off) the lower id:
    /// exactly one of the two orders makes a the slave.
    #[test]
    fn the_slave_is_the_finer_surface_else_the_lower_id_in_either_order() {
        let fine = surface(7, icosphere(0.05, 4), Vec3::zeros());
        let coarse = surface(2, plate(0.4, 0.4, 20, 20, ElementKind::Quad), Vec3::zeros());
        // a sphere of two copies, one moved far: the same mean area but for the last bits
        let copy = surface(9, icosphere(0.05, 4), Vec3::new(12.345, -6.789, 0.1));
        let (f, c, k) = ((fine.0, &fine.1), (coarse.0, &coarse.1), (copy.0, &copy.1));
        assert!(
            slave_is_a(f, c) && !slave_is_a(c, f),
            "the finer sphere, not the lower id"
        );
        assert!(
            slave_is_a(f, k) && !slave_is_a(k, f),
            "equal meshes: the lower id (7)"
        );
        for (a, b) in [(f, c), (c, f), (f, k), (k, f), (c, k), (k, c)] {
            assert_ne!(slave_is_a(a, b), slave_is_a(b, a), "one side per pair");
        }
    }

    /// Under `Auto` a pair runs one way only where one surface is clearly finer (mean
    /// segment area under 0.7 of the other's), the finer body's points; meshes of about
    /// one size run both ways; `Finer` and `Both` whatever the meshes. Either order of
    /// the pair gives the same sides.
    #[test]
    fn auto_sides_run_one_way_only_where_one_surface_is_clearly_finer() {
        let quads = |id, n| surface(id, plate(0.4, 0.4, n, n, ElementKind::Quad), Vec3::zeros());
        let sphere = surface(7, icosphere(0.05, 4), Vec3::zeros());
        let (p20, p22, p24) = (quads(1, 20), quads(2, 22), quads(3, 24));
        fn r(x: &(u32, Surface)) -> (u32, &Surface) {
            (x.0, &x.1)
        }
        let either_order = |a, b| {
            let s = [
                Sides::of(SegmentSides::Auto, a, b),
                Sides::of(SegmentSides::Auto, b, a),
            ];
            (s[0], s[1])
        };
        // (20/24)^2 = 0.69: one way, the 24 x 24 plate's points (b in the first order)
        assert_eq!(either_order(r(&p20), r(&p24)), (Sides::B, Sides::A));
        // (20/22)^2 = 0.83: both ways
        assert_eq!(either_order(r(&p20), r(&p22)), (Sides::Both, Sides::Both));
        assert_eq!(either_order(r(&sphere), r(&p20)), (Sides::A, Sides::B));
        assert_eq!(
            Sides::of(SegmentSides::Finer, r(&p20), r(&p22)),
            Sides::B,
            "finer: one way whatever the ratio"
        );
        assert_eq!(
            Sides::of(SegmentSides::Both, r(&sphere), r(&p20)),
            Sides::Both
        );
    }
}
